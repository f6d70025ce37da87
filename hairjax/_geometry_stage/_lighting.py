"""The set-up's steps that read the light (docs/model.md §7, §9, §13): the occluder seen
from the camera and the light it reflects, and the shadow method's plan for Ω with the
occluder's own shadow, a depth test in the light's view. Geometry, camera and light only,
in NumPy float64; `_setup` runs them in turn."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import numpy as np

from .._geometry._occluder import occluder_hits, occluder_light_view, occluder_visibility
from .._geometry._placement import Placement
from .._geometry._projection import View
from .._geometry._shadows import ShadowInputs
from .._scene._occluder import Occluder
from .._scene._scene import Scene
from .._values._light import Light
from .._values._strands import unit_rows

__all__ = ["OccluderView", "ShadowPlan", "occluder_view", "shadow_plan", "to_light"]


def to_light(light, points: np.ndarray) -> np.ndarray:
    """Unit vectors from `points` to the light (`[P, 3]`; 0 at a point light's position)."""
    if light.kind == "directional":
        d = -np.asarray(light.direction, dtype=np.float64)
        return np.broadcast_to(d / np.linalg.norm(d), points.shape)
    return unit_rows(np.asarray(light.position, dtype=np.float64) - points)


@dataclasses.dataclass(frozen=True)
class OccluderView:
    """The occluder seen from the camera (§9, §13): its depth at every pixel centre
    (`hit_depth`, `[H·W]`, inf where it is missed), the `pixel`s it covers (`[Q]`), its
    `surface` point there (`[Q, 3]`), its colour k and its direct light k·light·max(N·L, 0)
    (`[Q, 3]`)."""

    hit_depth: np.ndarray
    pixel: np.ndarray
    surface: np.ndarray
    color: np.ndarray
    direct: np.ndarray

    @property
    def opaque(self) -> np.ndarray:
        """`[H·W]` bool: the occluder covers the pixel centre."""
        return np.isfinite(self.hit_depth)


@dataclasses.dataclass(frozen=True)
class ShadowPlan:
    """The shadow method's `plan` (None without shadows) and, with an occluder, its
    visibility V from the light (§13) at the strand points (`light_visibility`, `[P]`) and
    at its own surface points (`occluder_visibility`, `[Q]`): 0 where it shadows them."""

    plan: Any = None
    light_visibility: np.ndarray | None = None
    occluder_visibility: np.ndarray | None = None


def occluder_view(occluder: Occluder, light: Light, view: View, lap: Callable[[str], None]) -> OccluderView:
    """The `occluder` hit by the camera's pixel rays, and the `light` it reflects (§9, §13)."""
    hit_depth, normal, hit_point = occluder_hits(view, occluder)
    pixel = np.flatnonzero(np.isfinite(hit_depth))
    surface = hit_point[pixel]
    # Lambert's max(N·L, 0) (§9): the clip fires on the occluder's unlit side.
    lambert = np.clip(np.sum(normal[pixel] * to_light(light, surface), axis=1), 0.0, None)
    color = np.asarray(occluder.color, np.float64)
    direct = color * np.asarray(light.color, dtype=np.float64) * lambert[:, None]
    lap("occluder")
    return OccluderView(hit_depth=hit_depth, pixel=pixel, surface=surface, color=color, direct=direct)


def shadow_plan(
    scene: Scene,
    segments: np.ndarray,
    seg_strand: np.ndarray,
    segment_alpha: np.ndarray | None,
    occluder: OccluderView | None,
    placement: Placement,
    lap: Callable[[str], None],
    light_raster=None,
    opacity: np.ndarray | None = None,
) -> ShadowPlan:
    """The shadow method's plan for Ω (§7), with an occluder's surface points among its
    receivers, and the occluder's own shadow: a depth test in the light's view (§13).
    `light_raster`: the light's frame and raster, where made already; `opacity`: the
    strand opacities the plan serves, where only those (`ShadowInputs`)."""
    if not scene.shadows.casts:
        return ShadowPlan()
    strands, light = scene.strands, scene.light
    shadow_inputs = ShadowInputs(
        strands.points,
        segments,
        seg_strand,
        strands.width,
        light,
        receivers=None if occluder is None else occluder.surface,
        segment_alpha=segment_alpha,
        width_units=strands.width_units,
        placement=placement,
        raster=light_raster,
        opacity=opacity,
    )
    plan = scene.shadows.setup(shadow_inputs)
    lap("shadow set-up")
    if occluder is None:
        return ShadowPlan(plan=plan)
    light_view = occluder_light_view(light, strands.points, scene.occluder, scene.shadows.resolution)
    depth_map, _, _ = occluder_hits(light_view, scene.occluder)
    shadows = ShadowPlan(
        plan=plan,
        light_visibility=occluder_visibility(light_view, depth_map, strands.points),
        occluder_visibility=occluder_visibility(light_view, depth_map, occluder.surface),
    )
    lap("occluder shadow")
    return shadows
