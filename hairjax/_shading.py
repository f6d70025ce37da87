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

# "scheuermann" is implemented in _scheuermann.py (its own parameters, ScheuermannParams).
SHADING_MODELS = ("kajiya-kay", "kajiya-kay-mirror", "scheuermann")


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


def specular_power(gap: Float[Array, ""], p: Float[Array, ""]) -> Float[Array, ""]:
    """max(b, 0)^p for the base b = 1 − `gap`, with `gap` = 1 − b as `kajiya_kay_terms`
    returns it: exp(p·log1p(−gap)), exactly 0 where b ≤ SPECULAR_BASE_EPS. Value and
    gradients (in `gap` and p) are finite for every gap and p > 0 (docs/model.md §8)."""
    # Double-where: fires where b = 1 − gap ≤ SPECULAR_BASE_EPS (the highlight cone's far
    # side and its edge); there the power is exactly 0 and log1p(−gap ≤ −1) is never evaluated.
    positive = 1 - gap > SPECULAR_BASE_EPS
    safe = jnp.where(positive, gap, 0.0)
    return jnp.where(positive, jnp.exp(p * jnp.log1p(-safe)), 0.0)


def kajiya_kay_terms(
    tangent: Float[Array, 3], to_light: Float[Array, 3], to_eye: Float[Array, 3],
    model: str = "kajiya-kay",
) -> tuple[Float[Array, ""], Float[Array, ""]]:
    """The geometric part of Kajiya-Kay at one point: (sin(T, L), gap), gap = 1 − b for the
    model's base b (docs/model.md §8); `specular_power(gap, p)` is max(b, 0)^p. No shading
    parameter enters.

    b^p has condition number p in b, so b is carried as its gap to 1, computed without
    cancellation. With θ_L, θ_V the angles of L and V to T (sin θ = ‖T × X‖, cos θ = T·X):

        kajiya-kay         b =  cos(θ_L − θ_V),  s = sin(θ_L − θ_V) = sin θ_L cos θ_V − cos θ_L sin θ_V
        kajiya-kay-mirror  b = −cos(θ_L + θ_V),  s = sin(θ_L + θ_V) = sin θ_L cos θ_V + cos θ_L sin θ_V

    and in both 1 − b = s²/(1 + b) (1 ∓ cos x = sin²x/(1 ± cos x)). Near the peak s is small:
    its absolute error of a few u (the unit roundoff) gives b^p a relative error of a few
    sqrt(2p)·u where b^p ≳ 1/e, not the ~p·u of rounding b itself; and s²/(1 + b) moves only
    relatively, by O(u), with the inputs' norms 1 ± O(u), where b moves by O(u) absolutely."""
    tl = jnp.dot(tangent, to_light)
    tv = jnp.dot(tangent, to_eye)
    # sin via the cross product: exact near 0, where sqrt(1 - cos²) loses all digits.
    sin_tl = safe_norm(jnp.cross(tangent, to_light))
    sin_tv = safe_norm(jnp.cross(tangent, to_eye))
    if model == "kajiya-kay":
        base = tl * tv + sin_tl * sin_tv  # cos(θ_L − θ_V)
        s = sin_tl * tv - tl * sin_tv  # sin(θ_L − θ_V)
    elif model == "kajiya-kay-mirror":
        base = sin_tl * sin_tv - tl * tv  # −cos(θ_L + θ_V)
        s = sin_tl * tv + tl * sin_tv  # sin(θ_L + θ_V)
    else:
        raise ValueError(f"unknown shading model {model!r}; expected one of {SHADING_MODELS}")
    # Double-where: fires where b ≤ 0 (power 0 there), so 1 + b → 0 at b = −1 never divides;
    # 1 − b, ≥ 1 there, keeps the power exactly 0 (fl(1 − b) ≥ 1 for b ≤ 0).
    near = base > 0
    gap = jnp.where(near, s * s / jnp.where(near, 1 + base, 1.0), 1 - base)
    return sin_tl, gap


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

    **Returns:** `(diffuse, specular)`, each RGB: Kd·sin(T, L) and Ks·max(b, 0)^p with
    b = (T·L)(T·V) ± sin(T, L) sin(T, V) (see docs/model.md §8).
    """
    sin_tl, gap = kajiya_kay_terms(tangent, to_light, to_eye, model)
    diffuse = params.kd * sin_tl
    specular = params.ks * specular_power(gap, params.shininess)
    return diffuse, specular
