"""Scheuermann hair shading (scheuermann-2004 slides 9–13, docs/model.md §17): the
parameters, the per-point maths (JAX, pure, written for one point; the model vmaps it:
`scheuermann`, `shift_tangent`, `strand_specular`, `scheuermann_diffuse`) and the model.
Its per-point inputs (normals, textures) are made in `_scheuermann_inputs.py`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any, ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._constants import SCHEUERMANN_DIFFUSE_FLOOR
from .._vectors import safe_norm, safe_normalize
from ._kajiya_kay import specular_power
from ._model import (
    AbstractShadingModel,
    PointInputs,
    Reflectance,
    RGBLike,
    ShadingPoints,
    check_params,
    register_shading_model,
    rgb_param,
    rgb_uniform,
    scalar_param,
    values_repr,
)
from ._scheuermann_inputs import ScheuermannMaps, ScheuermannPoints, scheuermann_inputs
from ._transforms import IDENTITY, LOG

__all__ = [
    "ScheuermannParams",
    "Scheuermann",
    "scheuermann",
    "scheuermann_terms",
    "shift_tangent",
    "strand_specular",
    "smoothstep_attenuation",
    "scheuermann_diffuse",
]


class ScheuermannParams(eqx.Module):
    """The differentiable parameters of the Scheuermann model (a pytree of arrays).

    **Fields:** `kd`, `ambient`, `primary_color`, `secondary_color`: RGB `[3]` (a scalar
    broadcasts); `primary_exponent`, `secondary_exponent`: the lobes' exponents p₁, p₂;
    `primary_shift`, `secondary_shift`: the tangent shifts s₁, s₂ along the strand normal
    (docs/model.md §17 says which way each moves the highlight); `kappa`: κ in τ = exp(−κΩ).
    Like `ShadingParams`, concrete values are checked at construction (colours ≥ 0,
    exponents > 0, shifts finite, κ ≥ 0); traced ones pass.
    """

    kd: Float[Array, 3]
    ambient: Float[Array, 3]
    primary_color: Float[Array, 3]
    primary_exponent: Float[Array, ""]
    primary_shift: Float[Array, ""]
    secondary_color: Float[Array, 3]
    secondary_exponent: Float[Array, ""]
    secondary_shift: Float[Array, ""]
    kappa: Float[Array, ""]

    def __init__(
        self,
        kd: RGBLike = 0.6,
        ambient: RGBLike = 0.0,
        primary_color: RGBLike = 0.3,
        primary_exponent: ArrayLike = 80.0,
        primary_shift: ArrayLike = 0.1,
        secondary_color: RGBLike = 0.2,
        secondary_exponent: ArrayLike = 20.0,
        secondary_shift: ArrayLike = -0.1,
        kappa: ArrayLike = 1.0,
    ):
        self.kd = rgb_param(kd)
        self.ambient = rgb_param(ambient)
        self.primary_color = rgb_param(primary_color)
        self.primary_exponent = scalar_param(primary_exponent)
        self.primary_shift = scalar_param(primary_shift)
        self.secondary_color = rgb_param(secondary_color)
        self.secondary_exponent = scalar_param(secondary_exponent)
        self.secondary_shift = scalar_param(secondary_shift)
        self.kappa = scalar_param(kappa)

    def __check_init__(self):
        check_params(
            self,
            colors=("kd", "ambient", "primary_color", "secondary_color"),
            positive=("primary_exponent", "secondary_exponent"),
            finite=("primary_shift", "secondary_shift"),
            non_negative=("kappa",),
        )

    def __repr__(self) -> str:
        return values_repr(self)


# --------------------------------------------------------------------------- per point (JAX)


def scheuermann_diffuse(normal: Float[Array, 3], to_light: Float[Array, 3]) -> Float[Array, ""]:
    """saturate(lerp(0.25, 1, N·L)) (slide 12); 0 for a point without normal (N = 0, §1's
    points without tangent: ambient only)."""
    wrapped = jnp.clip(
        SCHEUERMANN_DIFFUSE_FLOOR + (1 - SCHEUERMANN_DIFFUSE_FLOOR) * jnp.dot(normal, to_light), 0.0, 1.0
    )
    # Fires at points without tangent (N = 0 there by construction): no lit terms.
    return jnp.where(jnp.dot(normal, normal) > 0.5, wrapped, 0.0)


def shift_tangent(
    tangent: Float[Array, 3], normal: Float[Array, 3], shift: Float[ArrayLike, ""]
) -> Float[Array, 3]:
    """normalize(T + shift·N) (slide 10). N ⟂ T and both unit (or both 0) by construction
    (`strand_normals`), so |T + shift·N| = √(1 + shift²) and no guard is needed: a point
    without tangent keeps T' = 0."""
    return (tangent + shift * normal) / jnp.sqrt(1 + shift * shift)


def smoothstep_attenuation(x: Float[Array, ""]) -> Float[Array, ""]:
    """smoothstep(−1, 0, x) = t²(3 − 2t), t = clamp(x + 1, 0, 1) (slide 11's dirAtten).
    A polynomial of a clamp: value and gradient finite everywhere (the gradient is 0 at
    both clamp edges, so it is continuous)."""
    t = jnp.clip(x + 1.0, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def strand_specular(
    tangent: Float[Array, 3], half: Float[Array, 3], exponent: Float[ArrayLike, ""]
) -> Float[Array, ""]:
    """smoothstep(−1, 0, T·H) · sin(T, H)^p (slide 11) for unit T and H; 0 when either is
    the zero vector.

    sin(T, H) = ‖T × H‖ and, as for Kajiya-Kay (docs/model.md §8), the power is taken from
    the gap 1 − sin = cos²/(1 + sin), cos = T·H, without cancellation: near the peak
    (T ⟂ H) cos is small and its absolute rounding of a few u errs sin^p by ~2√p·u relative,
    not the ~p·u of rounding sin itself. 1 + sin ≥ 1, so the quotient never divides by 0.
    """
    cos = jnp.dot(tangent, half)
    sin = safe_norm(jnp.cross(tangent, half))
    # Fires where T or H is the zero vector (a point without tangent; L = −V, where the half
    # vector does not exist): cos² + sin² = 0 there, and the quotient would claim the peak.
    unit = cos * cos + sin * sin > 0.5
    gap = jnp.where(unit, cos * cos / (1 + sin), 1.0)
    return smoothstep_attenuation(cos) * specular_power(gap, exponent)


def scheuermann_terms(
    tangent: Float[Array, 3],
    normal: Float[Array, 3],
    to_light: Float[Array, 3],
    to_eye: Float[Array, 3],
    shift: Float[ArrayLike, ""],
    mask: Float[ArrayLike, ""],
    params: ScheuermannParams,
) -> tuple[Float[Array, ""], Float[Array, ""], Float[Array, ""]]:
    """The Scheuermann terms at one point before their colours (slide 12): the diffuse
    saturate(lerp(0.25, 1, N·L)), S(T₁, H, p₁) and m·S(T₂, H, p₂), with H = normalize(L + V),
    Tᵢ = normalize(T + (sᵢ + σ)N) and S the strand specular (`strand_specular`)."""
    # safe_normalize fires for L = −V (light exactly behind the point as seen): H = 0,
    # and strand_specular gives 0.
    half = safe_normalize(to_light + to_eye)
    t1 = shift_tangent(tangent, normal, params.primary_shift + shift)
    t2 = shift_tangent(tangent, normal, params.secondary_shift + shift)
    return (
        scheuermann_diffuse(normal, to_light),
        strand_specular(t1, half, params.primary_exponent),
        jnp.asarray(mask) * strand_specular(t2, half, params.secondary_exponent),
    )


def scheuermann(
    tangent: Float[Array, 3],
    normal: Float[Array, 3],
    to_light: Float[Array, 3],
    to_eye: Float[Array, 3],
    shift: Float[ArrayLike, ""],
    mask: Float[ArrayLike, ""],
    params: ScheuermannParams,
) -> tuple[Float[Array, 3], Float[Array, 3]]:
    """Unshadowed Scheuermann terms at one point (slide 12).

    **Arguments:** unit `tangent` T (root to tip), unit strand `normal` N ⟂ T, unit
    `to_light` L and `to_eye` V (from the point), the shift texture's value `shift` σ, the
    noise `mask` m, `params`.

    **Returns:** `(diffuse, specular)`, each RGB: Kd·saturate(lerp(0.25, 1, N·L)) and
    C₁·S(T₁, H, p₁) + m·C₂·S(T₂, H, p₂) (`scheuermann_terms`). The model multiplies both
    by the point's base colour (docs/model.md §17).
    """
    diffuse, s1, s2 = scheuermann_terms(tangent, normal, to_light, to_eye, shift, mask, params)
    return params.kd * diffuse, params.primary_color * s1 + params.secondary_color * s2


_SCHEUERMANN_PARAMS = (
    "kd",
    "ambient",
    "kappa",
    "primary_color",
    "primary_exponent",
    "primary_shift",
    "secondary_color",
    "secondary_exponent",
    "secondary_shift",
)
_SCHEUERMANN_MAPS = (
    "normal_center",
    "texture_seed",
    "shift_noise",
    "mask_noise",
    "base_texture",
    "alpha_texture",
    "occlusion",
    "hair_occlusion",
)


@register_shading_model
class Scheuermann(AbstractShadingModel):
    """scheuermann-2004's two shifted highlights (docs/model.md §17): the colour at a point
    is c·(ambient + τ·V·light·(Kd·diffuse + C₁·S₁ + m·C₂·S₂)), c the strand colour times the
    base texture and ambient occlusion; `maps` says how the per-point inputs are made."""

    params: ScheuermannParams = eqx.field(default_factory=lambda: ScheuermannParams())
    maps: ScheuermannMaps = eqx.field(static=True, default=ScheuermannMaps())

    name: ClassVar[str] = "scheuermann"
    params_type: ClassVar[type] = ScheuermannParams
    table_keys: ClassVar[tuple[str, ...]] = _SCHEUERMANN_PARAMS + _SCHEUERMANN_MAPS
    fittable: ClassVar[tuple[str, ...]] = (
        "kd",
        "primary_color",
        "primary_exponent",
        "primary_shift",
        "secondary_color",
        "secondary_exponent",
        "secondary_shift",
        "kappa",
    )
    searched: ClassVar[Mapping] = {
        "primary_exponent": LOG,
        "primary_shift": IDENTITY,
        "secondary_exponent": LOG,
        "secondary_shift": IDENTITY,
        "kappa": LOG,
    }
    gl_id: ClassVar[int | None] = 3

    def point_inputs(self, strands, tangent: np.ndarray) -> PointInputs:
        pts, factor, seg_alpha = scheuermann_inputs(strands, tangent, self.maps)
        return PointInputs(extra=pts, color_factor=factor, segment_alpha=seg_alpha)

    def reflectance(self, points: ShadingPoints, params: ScheuermannParams) -> Reflectance:
        pts: ScheuermannPoints = points.extra  # as JAX arrays here (the geometry stage's)
        normal, shift, mask = jnp.asarray(pts.normal), jnp.asarray(pts.shift), jnp.asarray(pts.mask)
        diffuse, s1, s2 = jax.vmap(scheuermann_terms, in_axes=(0, 0, 0, 0, 0, 0, None))(
            points.tangent, normal, points.to_light, points.to_eye, shift, mask, params
        )
        c = points.base_color
        return Reflectance(
            ambient={"ambient": c},
            lit={
                "kd": diffuse[:, None] * c,
                "primary_color": s1[:, None] * c,
                "secondary_color": s2[:, None] * c,
            },
        )

    def gl_uniforms(self, params: ScheuermannParams) -> dict:
        uniforms: dict[str, Any] = {
            f"scheuermann.{n}": rgb_uniform(getattr(params, n))
            for n in ("kd", "ambient", "primary_color", "secondary_color")
        }
        for n in ("primary_exponent", "secondary_exponent", "primary_shift", "secondary_shift"):
            uniforms[f"scheuermann.{n}"] = float(getattr(params, n))
        return uniforms

    def gl_attributes(self, inputs: PointInputs) -> list:
        pts = inputs.extra
        return [(pts.normal, "3f", "in_normal"), (np.stack([pts.shift, pts.mask], axis=1), "2f", "in_maps")]

    def table(self) -> dict[str, Any]:
        """[shading]: the parameters, then `maps`' keys (a texture as a list, no
        normal_center where the roots' centre is used)."""
        maps = {f.name: getattr(self.maps, f.name) for f in dataclasses.fields(self.maps)}
        if maps["normal_center"] is None:
            del maps["normal_center"]
        for key, value in maps.items():
            if isinstance(value, tuple):  # a texture or a point: TOML arrays
                maps[key] = [list(v) if isinstance(v, tuple) else v for v in value]
        return {**super().table(), **maps}

    @classmethod
    def from_table(cls, table) -> Scheuermann:
        """[shading] with model = "scheuermann": types here, ranges in ScheuermannParams
        and ScheuermannMaps."""
        params = ScheuermannParams(
            **table.given(
                **{
                    n: table.rgb(n, scalar=True)
                    for n in ("kd", "ambient", "primary_color", "secondary_color")
                },
                **{
                    n: table.number(n)
                    for n in (
                        "kappa",
                        "primary_exponent",
                        "primary_shift",
                        "secondary_exponent",
                        "secondary_shift",
                    )
                },
            )
        )
        for key, rgb in (("base_texture", True), ("alpha_texture", False), ("occlusion", False)):
            table.texture(key, rgb=rgb)
        maps = table.given(
            normal_center=table.vec3("normal_center"),
            texture_seed=table.integer("texture_seed"),
            shift_noise=table.number("shift_noise"),
            mask_noise=table.number("mask_noise"),
            base_texture=table.data.get("base_texture"),
            alpha_texture=table.data.get("alpha_texture"),
            occlusion=table.data.get("occlusion"),
            hair_occlusion=table.number("hair_occlusion"),
        )
        return cls(params=params, maps=ScheuermannMaps(**maps))
