"""The light as an input of the shading stage (docs/model.md §3, §10): its direction and
colour as a small pytree, `LightParams`, that the shading stage takes instead of the
geometry's light and differentiates through.

The geometry stage computes the light's vector L at every point, the light's colour and
the occluder's Lambert term k·light·max(N·L, 0) at the scene's light, and from that light
the shadows Ω and V (§7, §13), which carry no gradient in the light. A `LightParams`
replaces the first three in the shading stage; Ω and V stay those of the scene's light.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._errors import SceneError
from .._vectors import safe_normalize
from ._model import RGBLike, values_repr  # RGBLike: an array, a number or 3 numbers

if TYPE_CHECKING:
    from .._geometry_stage._stage import Geometry
    from .._values._light import Light

__all__ = ["LightParams", "directional_to_light", "light_rgb", "lit_to_light", "occluder_direct"]


class LightParams(eqx.Module):
    """The light's differentiable parameters (a pytree of arrays), for
    `shading_stage(geometry, params, light)`.

    **Fields:** `direction`: `[3]`, the way a directional light travels (any length but 0;
    L = −direction/‖direction‖ at every point), or None: the geometry's own L (a point
    light's, or the scene's direction as it is); `color`: RGB `[3]` (a scalar broadcasts),
    or None: the geometry's. Concrete values are checked at construction (`SceneError`
    naming `light.<field>`): finite, the direction not 0, the colour ≥ 0; traced ones
    (under `jax.grad`, a fit's step) pass.
    """

    direction: Float[Array, " 3"] | None
    color: Float[Array, " 3"] | None

    def __init__(self, direction: RGBLike | None = None, color: RGBLike | None = None):
        dtype = jnp.result_type(float)
        self.direction = None if direction is None else jnp.asarray(direction, dtype=dtype)
        self.color = None if color is None else jnp.broadcast_to(jnp.asarray(color, dtype=dtype), (3,))

    def __check_init__(self):
        if any(isinstance(x, jax.core.Tracer) for x in jax.tree_util.tree_leaves(self)):
            return
        if self.direction is not None:
            d = np.asarray(self.direction, dtype=np.float64)
            if d.shape != (3,) or not np.all(np.isfinite(d)) or not np.linalg.norm(d) > 0:
                raise SceneError(f"light.direction must be 3 finite numbers, not all 0, got {d.tolist()}")
        if self.color is not None:
            c = np.asarray(self.color, dtype=np.float64)
            if not np.all(np.isfinite(c)) or np.any(c < 0):
                raise SceneError(f"light.color must be finite and >= 0, got {c.tolist()}")

    def __repr__(self) -> str:
        return values_repr(self)

    @classmethod
    def from_light(cls, light: Light) -> LightParams:
        """The scene's light as parameters: a directional light's direction and colour; a
        point light's colour alone (its L stays the geometry's: a point light's position is
        not a parameter)."""
        direction = light.direction if light.kind == "directional" else None
        return cls(direction=direction, color=light.color)


def directional_to_light(direction: Float[Array, " 3"]) -> Float[Array, " 3"]:
    """L = −direction/‖direction‖, the unit vector towards a directional light (§3)."""
    # safe_normalize's guard fires only for a direction of length ≤ SAFE_NORM_EPS (refused
    # at construction, and a fit's direction has length ≥ 1): L = 0, no light.
    return -safe_normalize(direction)


def lit_to_light(geometry: Geometry, light: LightParams | None) -> Float[Array, "P 3"]:
    """L at every strand point: the geometry's, or `light`'s direction at every point."""
    if light is None or light.direction is None:
        return geometry.to_light
    return jnp.broadcast_to(directional_to_light(light.direction)[None, :], geometry.to_light.shape)


def light_rgb(geometry: Geometry, light: LightParams | None) -> Float[Array, " 3"]:
    """The light's colour: the geometry's, or `light`'s."""
    return geometry.light_rgb if light is None or light.color is None else light.color


def occluder_direct(geometry: Geometry, light: LightParams | None) -> Float[Array, "Q 3"] | None:
    """k·light·max(N·L, 0) at the occluder's pixels (§13), at `light`'s colour.

    The geometry keeps this term at the scene's light, not the occluder's normals N, so a
    new colour rescales it: max(N·L, 0) is read back from the channel where k·light is
    largest. A new direction would need N: it is refused (ValueError)."""
    direct = geometry.occluder_direct
    if direct is None or light is None:
        return direct
    if light.direction is not None:
        raise ValueError(
            "a light direction cannot be given for a scene with an occluder: the geometry stage "
            "keeps the occluder's Lambert term, not its normals (docs/model.md §3)"
        )
    if light.color is None:
        return direct
    assert geometry.occluder_color is not None  # set with occluder_direct
    scale = geometry.occluder_color * geometry.light_rgb
    c = jnp.argmax(scale)
    # Fires where k·light = 0 in every channel (a black occluder, whose direct term is 0
    # whatever the light, or a black scene light, whose Lambert term is lost): 0.
    lambert = jnp.where(scale[c] > 0, direct[:, c] / jnp.where(scale[c] > 0, scale[c], 1.0), 0.0)
    return geometry.occluder_color[None, :] * light.color[None, :] * lambert[:, None]
