"""The Scheuermann fit's model-specific part (docs/model.md §17; docs/fitting.md,
"Scheuermann scenes"): its parameters and image as `FitModel` asks for them.

Unlike Kajiya-Kay's, its image is not linear in gains that variable projection could solve
for: the solver iterates on every fitted parameter through the differentiable shading
stage; the geometry stage runs once per target. Colours are fitted through a softplus
(≥ 0), exponents and κ through exp (scale-free, > 0), shifts as they are.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from .._render import geometry_stage, shading_stage
from .._scene import Scene
from .._scheuermann import ScheuermannParams
from ._model import FitModel
from ._space import IDENTITY, LOG, SOFTPLUS

__all__ = ["SCHEUERMANN_FITTABLE", "MODEL", "TargetData", "prepare", "image"]

SCHEUERMANN_FITTABLE = ("kd", "primary_color", "primary_exponent", "primary_shift",
                        "secondary_color", "secondary_exponent", "secondary_shift", "kappa")
_COLOURS = ("kd", "primary_color", "secondary_color")
# The solver's space: colours through a softplus (≥ 0), exponents and κ through exp
# (scale-free, > 0), shifts as they are.
TRANSFORMS = {**{n: SOFTPLUS for n in _COLOURS},
              **{n: LOG for n in ("primary_exponent", "secondary_exponent", "kappa")},
              **{n: IDENTITY for n in ("primary_shift", "secondary_shift")}}


class TargetData(eqx.Module):
    """Per target: the geometry stage's output, the target and its √weights."""

    geometry: object
    target: jax.Array
    sqrt_weight: jax.Array


def prepare(scene: Scene, params: ScheuermannParams, names, target, sqrt_weight) -> TargetData:
    """One target's data (`FitModel.prepare`): every parameter reaches the shading stage, so
    only the geometry stage is run ahead."""
    return TargetData(geometry_stage(scene), jnp.asarray(target), jnp.asarray(sqrt_weight))


def image(data: TargetData, params: ScheuermannParams) -> jax.Array:
    """The target's RGB image `[HW, 3]` at `params` (`FitModel.image`)."""
    return shading_stage(data.geometry, params)[..., :3].reshape(-1, 3)


MODEL = FitModel(label="Scheuermann", shading_models=("scheuermann",),
                 params_type=ScheuermannParams, fittable=SCHEUERMANN_FITTABLE, colours=_COLOURS,
                 transforms=TRANSFORMS, prepare=prepare, image=image)
