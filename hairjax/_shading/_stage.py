"""The shading stage: point colours from the geometry stage and the shading parameters,
and the image they composite to (docs/model.md §6, §8, §13).

    colour = Σ_g params.g ⊙ ambient_g + light · τ · V · Σ_g params.g ⊙ lit_g
             + light · V · Σ_g params.g ⊙ scattered_g                          (× streak)

with the model's `Reflectance` terms (scattered: light scattered between fibres, §19),
τ = exp(−κΩ) (§7) and V the occluder's visibility (§13). Nothing here depends on which
model shades: the model object in the geometry (`Geometry.shading`) supplies its terms.

Every function takes an optional `light` (`LightParams`, `_light.py`): its direction and
colour replace the geometry's L, light colour and the occluder's Lambert term, and the
image is differentiable in them; Ω and V stay those of the scene's light (docs/model.md §3).
With `light=None` everything is the geometry's, as computed by the geometry stage.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._composite import composite
from ._light import LightParams, light_rgb, lit_to_light, occluder_direct
from ._model import Reflectance, ShadingPoints
from ._transmittance import transmittance

if TYPE_CHECKING:
    from .._geometry_stage._stage import Geometry

__all__ = [
    "shading_points",
    "light_factor",
    "scattered_factor",
    "combine",
    "point_colors",
    "occluder_colors",
    "shading_stage",
]


def shading_points(geometry: Geometry, light: LightParams | None = None) -> ShadingPoints:
    """The per-point inputs every model reads, from the geometry stage (L from `light`'s
    direction where it has one)."""
    return ShadingPoints(
        tangent=geometry.tangent,
        to_light=lit_to_light(geometry, light),
        to_eye=geometry.to_eye,
        base_color=geometry.base_color,
        extra=geometry.shading_inputs,
        omega=geometry.omega,
    )


def light_factor(geometry: Geometry, kappa, light: LightParams | None = None) -> Float[Array, "P 3"]:
    """light · τ · V per point: what the lit terms are multiplied by (§7, §13); the light's
    colour is `light`'s where it has one."""
    factor = jnp.broadcast_to(light_rgb(geometry, light)[None, :], geometry.tangent.shape)
    if geometry.omega is not None:
        factor = factor * transmittance(kappa, geometry.omega)[:, None]
    if geometry.light_visibility is not None:
        factor = factor * geometry.light_visibility[:, None]
    return factor


def scattered_factor(geometry: Geometry, light: LightParams | None = None) -> Float[Array, "P 3"]:
    """light · V per point: what the scattered terms are multiplied by (§19: light that
    came through the hair in front, so not τ)."""
    factor = jnp.broadcast_to(light_rgb(geometry, light)[None, :], geometry.tangent.shape)
    if geometry.light_visibility is not None:
        factor = factor * geometry.light_visibility[:, None]
    return factor


def combine(
    reflectance: Reflectance, params, light: Float[Array, "P 3"], scattered: Float[Array, "P 3"] | None = None
) -> Float[Array, "P 3"]:
    """Σ_g params.g ⊙ ambient_g + light ⊙ Σ_g params.g ⊙ lit_g (+ scattered ⊙ Σ_g params.g ⊙
    scattered_g where the model has scattered terms)."""

    def weighted(terms: dict):
        return sum(getattr(params, g)[None, :] * term for g, term in terms.items())

    colors = weighted(reflectance.ambient) + light * weighted(reflectance.lit)
    if reflectance.scattered:
        colors = colors + scattered * weighted(reflectance.scattered)
    return colors


def point_colors(geometry: Geometry, params, light: LightParams | None = None) -> Float[Array, "P 3"]:
    """Shaded colour at every strand point (Gouraud, kim-2003 §5): the model's reflectance
    lit by `light_factor`, times the streak factor (§16) where the scene has streaks.
    `light`: the light's direction and colour instead of the geometry's (module docstring)."""
    model = geometry.shading
    if not isinstance(params, model.params_type):
        raise TypeError(
            f"shading model {model.name!r} takes {model.params_type.__name__}, got {type(params).__name__}"
        )
    reflectance = model.reflectance(shading_points(geometry, light), params)
    colors = combine(
        reflectance,
        params,
        light_factor(geometry, params.kappa, light),
        scattered_factor(geometry, light) if reflectance.scattered else None,
    )
    if geometry.streak is not None:  # §16: the streak texture modulates the whole colour
        colors = colors * geometry.streak[:, None]
    return colors


def occluder_colors(geometry: Geometry, params, light: LightParams | None = None) -> Float[Array, "Q 3"]:
    """The occluder's colour at the pixels it covers (docs/model.md §13):
    k·ambient + τ·k·light·max(N·L, 0)·V, τ = exp(−κΩ) at its surface point. `light`: its
    colour instead of the geometry's (a direction is refused: `occluder_direct`)."""
    direct, color = occluder_direct(geometry, light), geometry.occluder_color
    if direct is None or color is None:
        raise ValueError("occluder_colors: the geometry has no occluder")
    if geometry.occluder_omega is not None:
        direct = direct * transmittance(params.kappa, geometry.occluder_omega)[:, None]
    if geometry.occluder_visibility is not None:
        direct = direct * geometry.occluder_visibility[:, None]
    return params.ambient[None, :] * color[None, :] + direct


@eqx.filter_jit
def shading_stage(geometry: Geometry, params, light: LightParams | None = None) -> Float[Array, "H W 4"]:
    """The image from the geometry stage and the shading parameters (`[H, W, 4]`):
    the composite of the point colours over the backdrop (the occluder's colour where it
    covers the pixel), alpha from the geometry stage.

    **Arguments:** `geometry` (`geometry_stage(scene)`); `params`, the shading model's
    parameters; `light` (`LightParams`, optional): the light's direction and colour instead
    of the scene's, differentiable. A direction makes the light directional, L the same at
    every point: give one only for a scene with a directional light (the geometry does not
    record the light's kind; `LightParams.from_light` gives a point light's colour alone),
    and not for one with an occluder (ValueError). Ω and V stay the scene light's
    (docs/model.md §3). `light=None`: the scene's light, exactly as without the argument.
    """
    rgb = composite(geometry, point_colors(geometry, params, light), paired=True)
    backdrop = geometry.backdrop
    if geometry.occluder_pixel is not None:
        backdrop = backdrop.at[geometry.occluder_pixel].set(occluder_colors(geometry, params, light))
    rgb = rgb + geometry.transmittance[:, None] * backdrop
    image = jnp.concatenate([rgb, geometry.alpha_channel[:, None]], axis=1)
    return image.reshape(geometry.height, geometry.width, 4)
