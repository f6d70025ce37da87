"""What the generic fit asks of one shading model (docs/fitting.md): `FitModel`, which
`_shading_fit.fit_model` builds for any registered shading model from the model's own
terms. Nothing else in the fit knows a model's parameters or image."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping

from .._shading._model import Plateau
from ._lit import RelativeTransform
from ._space import Transform

__all__ = ["FitModel", "Plateau"]


# Hashed by identity: it is a static part of the compiled steps, and each model has one.
@dataclasses.dataclass(frozen=True, eq=False)
class FitModel:
    """One shading model's fit.

    - `label`: its name in messages; `model_class`: the shading model class it fits;
      `params_type`: its parameters' class (ShadingParams, ScheuermannParams).
    - `fittable`: the names `fit` takes; `defaults`: those it fits when none are named (the
      shading model's `fittable`: the ambient gain, the light and the strands' opacity are
      fitted only where named); `colours`: the RGB ones (gains, and RGB searched
      parameters), which may also be fitted as one grey value; `transforms`: name → `Transform` from the
      solver's z (`_space.py`), or a `RelativeTransform` (the light's direction, `_lit.py`).
    - `prepare(scene, params, names, target, sqrt_weight) -> data`: per target, everything
      a step needs that no fitted parameter reaches (runs the geometry stage); `data` has
      `target` `[HW, 3]` and `sqrt_weight` `[HW, 1]`, as `target_arrays` gives them.
    - `image(data, params) -> [HW, 3]`: the target's RGB image at `params`.
    - `linear`: gains the image is linear in, solved for by variable projection
      (`_varpro.py`) with `gain_images(data, params) -> (fixed [HW, 3], ((gain,
      image [HW, 3]), ...))`, image = fixed + Σ gain⊙(its image); () for none.
    - `plateaus`: where a fit may stall with a parameter without effect (the shading
      model's `Plateau`s: the scans in the parameter's units, `_convergence.plateau_exit`
      takes them through the parameter's transform).
    - `grey`: the gains fitted as one grey value when the caller's `scalar` is None.
    """

    label: str
    model_class: type
    params_type: type
    fittable: tuple[str, ...]
    defaults: tuple[str, ...]
    colours: tuple[str, ...]
    transforms: Mapping[str, Transform | RelativeTransform]
    prepare: Callable
    image: Callable
    linear: tuple[str, ...] = ()
    gain_images: Callable | None = None
    plateaus: tuple[Plateau, ...] = ()
    grey: tuple[str, ...] = ()
