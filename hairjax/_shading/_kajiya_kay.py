"""Kajiya-Kay hair shading with kim-2003's cone (kim-2003 §5 and its Cg listing, Fig. 19;
docs/model.md §8).

Pure functions written for one point; batch them with `jax.vmap` (the model does). The
mirror cone (`_mirror.py`) and the lookup table (`_lookup.py`) reuse them with another
`cone`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._constants import SPECULAR_BASE_EPS
from .._vectors import safe_norm
from ._model import (
    AbstractShadingModel,
    Plateau,
    Reflectance,
    RGBLike,
    ShadingPoints,
    check_params,
    register_shading_model,
    rgb_param,
    rgb_uniform,
    values_repr,
)
from ._transforms import LOG

__all__ = [
    "ShadingParams",
    "KajiyaKay",
    "Cone",
    "seed_cone",
    "kajiya_kay",
    "kajiya_kay_terms",
    "specular_power",
    "read_kajiya_kay_params",
    "SHININESS_RANGE",
    "SHININESS_SCAN",
]

# The shininess we support, and where `fit` looks for a lower loss when it stops with Ks
# solved to 0 and the shininess without effect (docs/fitting.md, "When a fit has
# converged"): that range on a log grid, 1.5× apart.
SHININESS_RANGE = (0.5, 1e4)
SHININESS_SCAN = tuple(float(p) for p in np.geomspace(*SHININESS_RANGE, 25))


class ShadingParams(eqx.Module):
    """The differentiable parameters of the Kajiya-Kay models (a pytree of arrays).

    **Fields:** `kd`, `ks`, `ambient`: RGB `[3]` (a scalar broadcasts); `shininess`: the
    specular exponent p; `kappa`: κ in τ = exp(−κΩ).

    Concrete values are checked at construction (`SceneError` naming the field): gains
    ≥ 0, p > 0, κ ≥ 0, all finite; traced ones (under `jax.grad`, a fit's step) pass.
    """

    kd: Float[Array, 3]
    ks: Float[Array, 3]
    shininess: Float[Array, ""]
    kappa: Float[Array, ""]
    ambient: Float[Array, 3]

    def __init__(
        self,
        kd: RGBLike = 0.6,
        ks: RGBLike = 0.3,
        shininess: ArrayLike = 40.0,
        kappa: ArrayLike = 1.0,
        ambient: RGBLike = 0.0,
    ):
        self.kd = rgb_param(kd)
        self.ks = rgb_param(ks)
        self.shininess = jnp.asarray(shininess, dtype=jnp.result_type(float))
        self.kappa = jnp.asarray(kappa, dtype=jnp.result_type(float))
        self.ambient = rgb_param(ambient)

    def __check_init__(self):
        check_params(self, colors=("kd", "ks", "ambient"), positive=("shininess",), non_negative=("kappa",))

    def __repr__(self) -> str:
        return values_repr(self)


def specular_power(gap: Float[ArrayLike, "*shape"], p: Float[ArrayLike, ""]) -> Float[Array, "*shape"]:
    """max(b, 0)^p, elementwise, for the base b = 1 − `gap`, with `gap` = 1 − b as `kajiya_kay_terms`
    returns it: exp(p·log1p(−gap)), exactly 0 where b ≤ SPECULAR_BASE_EPS. Value and
    gradients (in `gap` and p) are finite for every gap and p > 0 (docs/model.md §8)."""
    # Double-where: fires where b = 1 − gap ≤ SPECULAR_BASE_EPS (the highlight cone's far
    # side and its edge); there the power is exactly 0 and log1p(−gap ≤ −1) is never evaluated.
    gap = jnp.asarray(gap)
    positive = 1 - gap > SPECULAR_BASE_EPS
    safe = jnp.where(positive, gap, 0.0)
    return jnp.where(positive, jnp.exp(p * jnp.log1p(-safe)), 0.0)


Cone = Callable[..., tuple[Float[Array, ""], Float[Array, ""]]]


def seed_cone(tl, tv, sin_tl, sin_tv):
    """kim-2003's retro-reflection cone: (b, s) = (cos(θ_L − θ_V), sin(θ_L − θ_V)) from
    cos θ = T·X and sin θ = ‖T × X‖ of L and V (docs/model.md §8)."""
    return tl * tv + sin_tl * sin_tv, sin_tl * tv - tl * sin_tv


def kajiya_kay_terms(
    tangent: Float[Array, 3],
    to_light: Float[Array, 3],
    to_eye: Float[Array, 3],
    cone: Cone = seed_cone,
) -> tuple[Float[Array, ""], Float[Array, ""]]:
    """The geometric part of Kajiya-Kay at one point: (sin(T, L), gap), gap = 1 − b for the
    `cone`'s base b (docs/model.md §8); `specular_power(gap, p)` is max(b, 0)^p. No shading
    parameter enters.

    b^p has condition number p in b, so b is carried as its gap to 1, computed without
    cancellation. With θ_L, θ_V the angles of L and V to T (sin θ = ‖T × X‖, cos θ = T·X):

        seed_cone    b =  cos(θ_L − θ_V),  s = sin(θ_L − θ_V) = sin θ_L cos θ_V − cos θ_L sin θ_V
        mirror_cone  b = −cos(θ_L + θ_V),  s = sin(θ_L + θ_V) = sin θ_L cos θ_V + cos θ_L sin θ_V

    and in both 1 − b = s²/(1 + b) (1 ∓ cos x = sin²x/(1 ± cos x)). Near the peak s is small:
    its absolute error of a few u (the unit roundoff) gives b^p a relative error of a few
    sqrt(2p)·u where b^p ≳ 1/e, not the ~p·u of rounding b itself; and s²/(1 + b) moves only
    relatively, by O(u), with the inputs' norms 1 ± O(u), where b moves by O(u) absolutely."""
    tl = jnp.dot(tangent, to_light)
    tv = jnp.dot(tangent, to_eye)
    # sin via the cross product: exact near 0, where sqrt(1 - cos²) loses all digits.
    sin_tl = safe_norm(jnp.cross(tangent, to_light))
    sin_tv = safe_norm(jnp.cross(tangent, to_eye))
    base, s = cone(tl, tv, sin_tl, sin_tv)
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
    cone: Cone = seed_cone,
) -> tuple[Float[Array, 3], Float[Array, 3]]:
    """Unshadowed Kajiya-Kay terms at one point.

    **Arguments:** unit `tangent` T, unit `to_light` L and `to_eye` V (from the point),
    `params`, `cone` (`seed_cone`: kim-2003's retro-reflection cone; `mirror_cone`: the
    mirror cone, hairjax/_shading/_mirror.py).

    **Returns:** `(diffuse, specular)`, each RGB: Kd·sin(T, L) and Ks·max(b, 0)^p with
    b = (T·L)(T·V) ± sin(T, L) sin(T, V) (see docs/model.md §8).
    """
    sin_tl, gap = kajiya_kay_terms(tangent, to_light, to_eye, cone)
    diffuse = params.kd * sin_tl
    specular = params.ks * specular_power(gap, params.shininess)
    return diffuse, specular


def read_kajiya_kay_params(table) -> ShadingParams:
    """[shading]'s Kajiya-Kay parameters (types here; ranges are ShadingParams' checks)."""
    return ShadingParams(
        **table.given(
            kd=table.rgb("kd", scalar=True),
            ks=table.rgb("ks", scalar=True),
            shininess=table.number("shininess"),
            kappa=table.number("kappa"),
            ambient=table.rgb("ambient", scalar=True),
        )
    )


@register_shading_model
class KajiyaKay(AbstractShadingModel):
    """Kajiya-Kay with kim-2003's cone (docs/model.md §8): the colour at a point is
    ambient·c + τ·V·light·(Kd·sin(T, L)·c + Ks·max(b, 0)^p)."""

    params: ShadingParams = eqx.field(default_factory=ShadingParams)

    name: ClassVar[str] = "kajiya-kay"
    params_type: ClassVar[type] = ShadingParams
    table_keys: ClassVar[tuple[str, ...]] = ("kd", "ks", "shininess", "kappa", "ambient")
    fittable: ClassVar[tuple[str, ...]] = ("kd", "ks", "shininess", "kappa")
    searched: ClassVar[Mapping] = {"shininess": LOG, "kappa": LOG}
    # With Ks solved to 0 the shininess has no effect: a plateau the fit leaves by scanning it.
    plateaus: ClassVar[tuple[Plateau, ...]] = (Plateau("shininess", SHININESS_SCAN, gain="ks"),)
    ranges: ClassVar[Mapping[str, tuple[float, float]]] = {"shininess": SHININESS_RANGE}
    gl_id: ClassVar[int | None] = 0
    # The cone, as a class attribute (a function, not a field): the mirror model swaps it.
    cone: ClassVar[Cone] = staticmethod(seed_cone)

    def reflectance(self, points: ShadingPoints, params: ShadingParams) -> Reflectance:
        sin_tl, gap = jax.vmap(kajiya_kay_terms, in_axes=(0, 0, 0, None))(
            points.tangent, points.to_light, points.to_eye, type(self).cone
        )
        spec = specular_power(gap, params.shininess)
        return Reflectance(
            ambient={"ambient": points.base_color},
            lit={
                "kd": sin_tl[:, None] * points.base_color,
                "ks": jnp.broadcast_to(spec[:, None], points.base_color.shape),
            },
        )

    def gl_uniforms(self, params: ShadingParams) -> dict:
        return {
            "shading.kd": rgb_uniform(params.kd),
            "shading.ks": rgb_uniform(params.ks),
            "shading.ambient": rgb_uniform(params.ambient),
            "shading.shininess": float(params.shininess),
        }

    @classmethod
    def from_table(cls, table) -> KajiyaKay:
        return cls(params=read_kajiya_kay_params(table))
