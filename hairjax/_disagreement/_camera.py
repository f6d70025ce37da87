"""The camera side of the band: pixels whose centre lies within rounding of a segment
end (docs/model.md §5), with each fragment's compositing weight, and the occluder's
outline (§9)."""

from __future__ import annotations

import numpy as np

from .._cache import cached
from .._geometry._occluder import interpolation_bound, occluder_hits, silhouette_pixels
from .._geometry._raster import Fragments, rasterize, ribbon_widths
from .._geometry_stage._setup import prepare, visibility_order
from .._scene._scene import Scene
from ._tolerances import OCCLUDER_EDGE_DELTA, OCCLUDER_VERTEX_STEP, PIXEL_TOL, s_delta

__all__ = ["over_weights_numpy", "end_band", "segment_opacity", "camera_risk", "camera_band"]


def over_weights_numpy(alpha: np.ndarray, pixel: np.ndarray) -> np.ndarray:
    """Compositing weights α_k T_k (docs/model.md §6) of fragments sorted by pixel, front
    to back within a pixel, by cumulative products in NumPy: independent of the renderer's
    JAX scan, and no compilation per fragment count."""
    weights = np.empty(len(alpha))
    starts = np.flatnonzero(np.r_[True, pixel[1:] != pixel[:-1]]) if len(pixel) else np.zeros(0, int)
    for lo, hi in zip(starts, np.r_[starts[1:], len(pixel)]):
        transmitted = np.cumprod(1.0 - alpha[lo:hi])
        weights[lo:hi] = alpha[lo:hi] * np.r_[1.0, transmitted[:-1]]
    return weights


def end_band(xy0, xy1, z0, z1, width, w, h, perspective) -> tuple[Fragments, np.ndarray]:
    """Fragments of the ribbons lengthened by δ = `s_delta` at both ends, and which of them
    lie within δ of an end (present lengthened, absent shortened by δ)."""
    delta = s_delta(w, h)
    d = xy1 - xy0
    u = d / np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-300)
    grow = rasterize(xy0 - delta * u, xy1 + delta * u, z0, z1, width, w, h, perspective)
    shrink = rasterize(xy0 + delta * u, xy1 - delta * u, z0, z1, width, w, h, perspective)
    key = lambda f: f.segment.astype(np.int64) * (w * h) + f.pixel  # noqa: E731
    return grow, ~_member(key(grow), key(shrink))


def _member(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """`np.isin(a, b)` for int64 keys, by a sort of `b` and a binary search: 0.26 s where
    `np.isin` took 5.8 s on the default scene's 5.5 M fragments (NumPy 2.4)."""
    if b.size == 0:
        return np.zeros(a.shape, bool)
    ordered = np.sort(b)
    at = np.minimum(np.searchsorted(ordered, a), ordered.size - 1)  # fires for keys past the last
    return ordered[at] == a


def segment_opacity(scene: Scene) -> np.ndarray:
    """Each segment's opacity: its strand's a, times the alpha texture of a Scheuermann
    scene (docs/model.md §17) — a smaller α in front lets more weight through behind."""
    s = scene.strands
    opacity = s.alpha[s.strand_of_point[s.segments()[:, 0]]]
    texture = prepare(scene).shading_inputs.segment_alpha
    return opacity if texture is None else opacity * texture


def camera_risk(scene) -> dict:
    """The camera side of `renderer_band`, cached per scene (`_cache`): per pixel the
    summed weight of fragments near a segment end, the pixels in the band whatever the
    colour, and each fragment's pixel, weight and segment ends (for the light side)."""
    return cached(scene, "disagreement band: camera", lambda: _camera_risk(scene))


def _camera_risk(scene) -> dict:
    cam = scene.camera
    hw = cam.width * cam.height
    view, xy, depth, segments, order = visibility_order(scene)
    near_first = order[::-1]
    s0, s1 = segments[near_first, 0], segments[near_first, 1]
    strand = scene.strands.strand_of_point[s0]
    width = ribbon_widths(
        scene.strands.width[strand],
        scene.strands.width_units,
        depth[s0],
        depth[s1],
        view.focal,
        view.perspective,
    )
    frags, near_end = end_band(xy[s0], xy[s1], depth[s0], depth[s1], width, cam.width, cam.height, True)
    sort = np.argsort(frags.pixel, kind="stable")  # front to back within a pixel
    pixel = np.asarray(frags.pixel)[sort]  # a host raster
    seg = frags.segment[sort]
    alpha = segment_opacity(scene)[near_first[seg]] * np.asarray(frags.coverage)[sort]
    weights = over_weights_numpy(alpha, pixel)
    near_end = near_end[sort]
    always = np.zeros(hw, bool)
    if scene.occluder is not None:
        # The occluder's outline and jumps, and hair fragments at its own depth.
        always |= silhouette_pixels(view, scene.occluder, OCCLUDER_EDGE_DELTA)
        always |= interpolation_bound(view, scene.occluder, scene.light, OCCLUDER_VERTEX_STEP) > PIXEL_TOL
        hit, _, _ = occluder_hits(view, scene.occluder)
        close = np.abs(frags.depth - hit[frags.pixel]) < 1e-5 * np.abs(hit[frags.pixel])
        always[frags.pixel[close]] = True
    return dict(
        camera=np.bincount(pixel, np.where(near_end, weights, 0.0), minlength=hw),
        always=always,
        pixel=pixel,
        weights=weights,
        near_end=near_end,
        ends=(s0[seg], s1[seg]),
    )


def camera_band(scene, colour_bound: float) -> np.ndarray:
    """Pixels (`bool[H·W]`, row-major) a camera-side discontinuity within rounding can move
    by more than PIXEL_TOL, given the renderers' Ω are the same (as tests/gl/test_renderer.py's
    camera pass, which hands JAX's Ω to GL). See `renderer_band` for the bound."""
    risk = camera_risk(scene)
    camera, always = risk["camera"], risk["always"]
    return (camera * colour_bound > PIXEL_TOL) | always
