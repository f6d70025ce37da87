"""The outcome of `hairjax.fit`, and the error it raises for bad input (docs/fitting.md)."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from ._lit import light_field

__all__ = ["FitResult", "FitError", "FitNotConverged"]


class FitError(ValueError):
    """Bad fit input (unknown parameter, target size, NaN pixels, …), raised before work."""


class FitNotConverged(RuntimeError):
    """A fit that stopped without converging, raised where `FitStop(throw=True)`; `result`
    is the `FitResult` it would have returned (its `termination` says why it stopped)."""

    def __init__(self, result: FitResult):
        super().__init__(f"the fit did not converge: {result.termination}")
        self.result = result


@dataclasses.dataclass(frozen=True)
class FitResult:
    """The outcome of `fit`.

    `params`, `initial`: ShadingParams (ScheuermannParams for a Scheuermann scene);
    `loss`: ½‖r‖² after each step (index 0: initial);
    `steps`, `time_s` (after the geometry stage), `termination` (why it stopped);
    `restarts`: times the solver's tolerance test passed where Gauss-Newton still predicted a
    decrease, and the solver was started afresh from its point (docs/fitting.md);
    `std_error`: name → standard error (array like the parameter) from (JᵀJ)⁻¹σ², or
    None where it is not defined; `undetermined`: names the data cannot determine;
    `rmse` over the fitted pixels; `geometry_s`: time of the geometry stages;
    `light`, `initial_light`: the fitted and the start's `LightParams` where the fit fitted
    or held the light (docs/fitting.md, "Fitting the light"), else None. `get(name)`
    reads any fitted name, the light's included; `holdout_rmse`: the RMSE on the held-out
    targets (`fit`'s `holdout`), else None; `alpha`, `initial_alpha`: the strands' fitted
    and starting opacity where the fit fitted it (docs/fitting.md, "Fitting the strands'
    opacity"), else None.
    """

    params: Any  # the shading model's parameters (its `params_type`)
    initial: Any
    fitted: tuple[str, ...]
    loss: list
    steps: int
    time_s: float
    geometry_s: float
    termination: str
    std_error: dict
    undetermined: tuple[str, ...]
    rmse: float
    restarts: int = 0
    light: Any = None
    initial_light: Any = None
    holdout_rmse: float | None = None
    alpha: float | None = None
    initial_alpha: float | None = None

    def get(self, name: str, initial: bool = False):
        """The fitted (or, with `initial`, the start's) value of `name`: a field of the
        model's parameters, or light_direction, light_color (None without a light)."""
        params, light = (self.initial, self.initial_light) if initial else (self.params, self.light)
        if name == "alpha":
            return self.initial_alpha if initial else self.alpha
        field = light_field(name)
        if field is None:
            return getattr(params, name)
        return None if light is None else getattr(light, field)

    def to_json(self) -> dict:
        def value(p, name):
            v = np.asarray(getattr(p, name), dtype=float)
            return v.tolist() if v.ndim else float(v)

        # The parameters' fields: kd, ks, shininess, kappa, ambient for ShadingParams.
        names = [f.name for f in dataclasses.fields(self.params)]

        def light(p):
            if p is None:
                return None
            return {f: None if getattr(p, f) is None else value(p, f) for f in ("direction", "color")}

        return {
            "params": {n: value(self.params, n) for n in names},
            "initial": {n: value(self.initial, n) for n in names},
            "fitted": list(self.fitted),
            "std_error": {
                k: (None if v is None else np.asarray(v, float).tolist()) for k, v in self.std_error.items()
            },
            "undetermined": list(self.undetermined),
            "steps": self.steps,
            "time_s": self.time_s,
            "geometry_s": self.geometry_s,
            "loss": [float(x) for x in self.loss],
            "rmse": self.rmse,
            "holdout_rmse": self.holdout_rmse,
            "alpha": self.alpha,
            "initial_alpha": self.initial_alpha,
            "termination": self.termination,
            "restarts": self.restarts,
            "light": light(self.light),
            "initial_light": light(self.initial_light),
        }
