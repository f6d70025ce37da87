"""The light among a fit's parameters (docs/fitting.md, "Fitting the light"): `LitParams`,
a model's parameters and the light's as one point of the solver's space, and the
transform the light's direction is searched through.

`light_direction` is searched in the plane tangent to the unit sphere at a reference
direction r (the fit's start; at the fitted direction for the standard errors):

    x = normalise(r + a·e₁ + b·e₂),   (a, b) ∈ ℝ²,   e₁, e₂ ⟂ r orthonormal,

the central (gnomonic) projection. x is a unit vector for every (a, b), and
‖r + a·e₁ + b·e₂‖² = 1 + a² + b² ≥ 1 never divides by 0; (a, b) = 0 is r, and near it
(a, b) are the angles of x to r along e₁ and e₂ (tan θ = ‖(a, b)‖). It reaches every
direction less than 90° from r: a fit can turn the light by up to that from its start.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any, NamedTuple

import jax.numpy as jnp

from .._shading._light import LightParams
from ._point import ExtendedParams

__all__ = ["LIGHT_NAMES", "light_field", "LitParams", "RelativeTransform", "PLANE", "plane_basis"]

# The fit's names of the light's parameters, and the LightParams field each one is.
LIGHT_NAMES = ("light_direction", "light_color")
_FIELD = {"light_direction": "direction", "light_color": "color"}


def light_field(name: str) -> str | None:
    """The `LightParams` field of a fit's name (None for a model's parameter)."""
    return _FIELD.get(name)


class LitParams(ExtendedParams):
    """A model's parameters (`shading`) and the light's (`light`, `LightParams`) as one
    point of a fit that fits the light or holds it at a given value. `get(name)` reads
    light_direction and light_color from the light, every other name from `shading`."""

    shading: Any
    light: LightParams

    def get(self, name: str):
        return getattr(self.light, _FIELD[name]) if name in _FIELD else getattr(self.shading, name)

    def replace(self, values: dict) -> LitParams:
        """These parameters with some replaced (`values`: name → array), each part through
        its own constructor (whose checks pass traced values)."""
        light = {_FIELD[n]: v for n, v in values.items() if n in _FIELD}
        shading = {n: v for n, v in values.items() if n not in _FIELD}
        return LitParams(
            dataclasses.replace(self.shading, **shading), dataclasses.replace(self.light, **light)
        )


class RelativeTransform(NamedTuple):
    """A transform from the solver's z (`size` entries) to a parameter x that depends on a
    reference value r of the parameter (the point the fit's space is built around):
    `forward(z, r)`, `inverse(x, r)`."""

    forward: Callable
    inverse: Callable
    size: int
    floored: bool = False


def plane_basis(r):
    """(unit r, e₁, e₂): e₁, e₂ orthonormal and ⟂ r, from the world axis least aligned
    with r (so e₁ is never made from a vector nearly parallel to r)."""
    r = r / jnp.linalg.norm(r)  # r is a reference direction, never 0 (LightParams checks it)
    axis = jnp.eye(3, dtype=r.dtype)[jnp.argmin(jnp.abs(r))]
    e1 = axis - jnp.dot(axis, r) * r
    e1 = e1 / jnp.linalg.norm(e1)  # ≥ √(2/3): the least aligned axis is ≤ 1/√3 along r
    return r, e1, jnp.cross(r, e1)


def _plane_forward(z, r):
    r, e1, e2 = plane_basis(r)
    x = r + z[0] * e1 + z[1] * e2
    return x / jnp.sqrt(jnp.sum(x * x))  # ‖x‖² = 1 + a² + b² ≥ 1: no guard needed


def _plane_inverse(x, r):
    r, e1, e2 = plane_basis(r)
    # x·r > 0 for every x the forward map gives; a start more than 90° from r cannot occur
    # (the start is r itself: z = 0).
    return jnp.stack([jnp.dot(x, e1), jnp.dot(x, e2)]) / jnp.dot(x, r)


# light_direction's transform: the tangent plane at the reference direction (module docstring).
PLANE = RelativeTransform(_plane_forward, _plane_inverse, size=2)
