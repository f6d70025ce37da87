"""The outcome of `hairjax.fit`, and the error it raises for bad input (docs/fitting.md)."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

__all__ = ["FitResult", "FitError"]


class FitError(ValueError):
    """Bad fit input (unknown parameter, target size, NaN pixels, …), raised before work."""


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
    `rmse` over the fitted pixels; `geometry_s`: time of the geometry stages.
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

    def to_json(self) -> dict:
        def value(p, name):
            v = np.asarray(getattr(p, name), dtype=float)
            return v.tolist() if v.ndim else float(v)

        # The parameters' fields: kd, ks, shininess, kappa, ambient for ShadingParams.
        names = [f.name for f in dataclasses.fields(self.params)]
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
            "termination": self.termination,
            "restarts": self.restarts,
        }
