"""The occluder's part of the band (docs/model.md §13): where GL's occluder light — V
and the occluder's own Ω — may differ within float32 rounding."""

from __future__ import annotations

import numpy as np

from .._geometry._occluder import occluder_hits, occluder_light_view, shadow_bias, silhouette_pixels
from .._geometry._shadows import light_frame, with_receivers
from .._geometry_stage._setup import prepare
from ._light import light_band
from ._tolerances import OCCLUDER_EDGE_DELTA

__all__ = ["occluder_light_uncertainty"]


def occluder_light_uncertainty(scene) -> tuple[np.ndarray, np.ndarray]:
    """(strand points `bool[P]`, pixels `bool[H·W]`) whose occluder light (docs/model.md
    §13) GL may compute differently within float32 rounding: V at a point within 1e-4 texel
    of a texel edge of the occluder's light raster, at a texel within OCCLUDER_EDGE_DELTA
    of the occluder's outline there, or within 1e-5 (relative) of the bias threshold; and
    at an occluder pixel, also Ω when its surface point lies within 1e-4 texel of an
    opacity-map texel edge or within rounding of a boundary of its depth (the method's
    `LightBand.receivers`: opacity maps' planes, deep maps' last boundary). Not covered: an
    occluder point's Ω moved by hair fragments near their segment ends (as
    `omega_uncertainty` bounds for strand points). All False without an occluder or
    shadows."""

    cam, s = scene.camera, scene.strands
    points_out, pixels_out = np.zeros(s.num_points, bool), np.zeros(cam.width * cam.height, bool)
    setup = prepare(scene)
    if setup.occluder_pixel is None or setup.shadow is None:
        return points_out, pixels_out
    _, _, hit_point = occluder_hits(setup.view, scene.occluder)
    surface = hit_point[setup.occluder_pixel]
    everything = np.concatenate([s.points, surface])
    r = scene.shadows.resolution

    def near_edge(xy):
        frac = xy - np.floor(xy)
        return np.any(np.minimum(frac, 1 - frac) < 1e-4, axis=1)

    view = occluder_light_view(scene.light, s.points, scene.occluder, r)
    depth_map, _, _ = occluder_hits(view, scene.occluder)
    xy, z = view.project(everything)
    tx = np.clip(np.floor(np.clip(xy[:, 0], -1, r)), 0, r - 1).astype(np.int64)
    ty = np.clip(np.floor(np.clip(xy[:, 1], -1, r)), 0, r - 1).astype(np.int64)
    texel = ty * r + tx
    outline = silhouette_pixels(view, scene.occluder, OCCLUDER_EDGE_DELTA)
    blocker = depth_map[texel]
    # Fires where the texel holds no occluder (∞): no threshold to be near.
    gap = np.where(np.isfinite(blocker), z - blocker - shadow_bias(view, z), np.inf)
    unsure = near_edge(xy) | outline[texel] | (np.abs(gap) < 1e-5 * np.maximum(np.abs(z), 1e-300))
    frame = with_receivers(
        light_frame(s.points, s.segments(), s.width, scene.light, r, s.width_units), surface
    )
    receiver = slice(s.num_points, None)
    unsure[receiver] |= near_edge(frame.xy[receiver])
    near_boundary = light_band(scene.shadows).receivers
    if near_boundary is not None:  # a receiver's depth near a boundary may fall on either side
        index = np.arange(s.num_points, len(frame.depth))
        unsure[receiver] |= near_boundary(scene.shadows, setup.shadow, frame, index)
    points_out[:] = unsure[: s.num_points]
    pixels_out[setup.occluder_pixel] = unsure[receiver]
    return points_out, pixels_out
