"""Kajiya-Kay hair shading (kim-2003 §5 and its Cg listing, Fig. 19).

Pure functions written for one point; batch them with `jax.vmap` (the renderer does).
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from ._constants import SPECULAR_BASE_EPS
from ._vectors import safe_norm

__all__ = ["ShadingParams", "kajiya_kay", "kajiya_kay_terms", "specular_power", "SHADING_MODELS"]

SHADING_MODELS = ("kajiya-kay", "kajiya-kay-mirror")


def _rgb(x) -> Float[Array, 3]:
    return jnp.broadcast_to(jnp.asarray(x, dtype=jnp.result_type(float)), (3,))


class ShadingParams(eqx.Module):
    """The differentiable shading parameters (a pytree of arrays).

    **Fields:** `kd`, `ks`, `ambient`: RGB `[3]` (a scalar broadcasts); `shininess`: the
    specular exponent p; `kappa`: κ in τ = exp(−κΩ).
    """

    kd: Float[Array, 3]
    ks: Float[Array, 3]
    shininess: Float[Array, ""]
    kappa: Float[Array, ""]
    ambient: Float[Array, 3]

    def __init__(self, kd: ArrayLike = 0.6, ks: ArrayLike = 0.3, shininess: ArrayLike = 40.0,
                 kappa: ArrayLike = 1.0, ambient: ArrayLike = 0.0):
        self.kd = _rgb(kd)
        self.ks = _rgb(ks)
        self.shininess = jnp.asarray(shininess, dtype=jnp.result_type(float))
        self.kappa = jnp.asarray(kappa, dtype=jnp.result_type(float))
        self.ambient = _rgb(ambient)


def specular_power(base: Float[Array, ""], p: Float[Array, ""]) -> Float[Array, ""]:
    """max(base, 0)^p with finite value and gradients for base → 0 and large p."""
    # Double-where: fires where the base is ≤ SPECULAR_BASE_EPS (the highlight cone's far
    # side and its edge); there the power is exactly 0 and log(base) is never evaluated.
    positive = base > SPECULAR_BASE_EPS
    safe = jnp.where(positive, base, 1.0)
    return jnp.where(positive, jnp.exp(p * jnp.log(safe)), 0.0)


def kajiya_kay_terms(
    tangent: Float[Array, 3], to_light: Float[Array, 3], to_eye: Float[Array, 3],
    model: str = "kajiya-kay",
) -> tuple[Float[Array, ""], Float[Array, ""]]:
    """The geometric part of Kajiya-Kay at one point: (sin(T, L), b), with
    b = (T·L)(T·V) ± sin(T, L) sin(T, V) (docs/model.md §8). No shading parameter enters."""
    tl = jnp.dot(tangent, to_light)
    tv = jnp.dot(tangent, to_eye)
    # sin via the cross product: exact near 0, where sqrt(1 - cos²) loses all digits.
    sin_tl = safe_norm(jnp.cross(tangent, to_light))
    sin_tv = safe_norm(jnp.cross(tangent, to_eye))
    if model == "kajiya-kay":
        base = tl * tv + sin_tl * sin_tv
    elif model == "kajiya-kay-mirror":
        base = sin_tl * sin_tv - tl * tv
    else:
        raise ValueError(f"unknown shading model {model!r}; expected one of {SHADING_MODELS}")
    return sin_tl, base


def kajiya_kay(
    tangent: Float[Array, 3],
    to_light: Float[Array, 3],
    to_eye: Float[Array, 3],
    params: ShadingParams,
    model: str = "kajiya-kay",
) -> tuple[Float[Array, 3], Float[Array, 3]]:
    """Unshadowed Kajiya-Kay terms at one point.

    **Arguments:** unit `tangent` T, unit `to_light` L and `to_eye` V (from the point),
    `params`, `model` ("kajiya-kay": the seed's retro-reflection cone;
    "kajiya-kay-mirror": the mirror cone).

    **Returns:** `(diffuse, specular)`, each RGB: Kd·sin(T, L) and Ks·base^p with
    base = (T·L)(T·V) ± sin(T, L) sin(T, V) (see docs/model.md §8).
    """
    sin_tl, base = kajiya_kay_terms(tangent, to_light, to_eye, model)
    diffuse = params.kd * sin_tl
    specular = params.ks * specular_power(base, params.shininess)
    return diffuse, specular
