"""Where the JAX and GL renderers may differ: discontinuities of the model within float32
rounding (docs/model.md §11).

The model has discontinuities: a pixel centre belongs to a segment only for 0 ≤ s < L
(§5), a light-space fragment adds to the slice its depth falls in and a point reads the
texels around the one it falls in (§7), `exact` counts fragments strictly nearer than the
point, and the occluder is point-sampled (§9). GLSL computes in float32, JAX in float64
(or float32 in another order of operations), so a pixel centre, fragment or point within
rounding of such a boundary may land on either side. Everything here is computed from the
geometry alone, in NumPy (JAX only for the rasteriser's kernel and the geometry stage's Ω),
independently of both renderers' per-pixel code:

- `camera_band`: pixels a camera-side boundary within rounding can move by > PIXEL_TOL
  when both renderers use one Ω (tests/test_gl.py's camera pass);
- `omega_uncertainty`, `shadow_band`: how much, and at which points, a light-side
  boundary within rounding can change Ω; `transmittance_uncertainty`: what that does to τ
  for any κ;
- `renderer_band`: pixels either can move by > PIXEL_TOL — what a fit to GL-rendered
  targets masks (docs/fitting.md, experiments/01_fit_recovery.py).

Tolerances (tests/test_gl.py gives the measurements behind them):
- PIXEL_TOL, TAU_TOL = 1e-4 per pixel / per τ: float32 arithmetic on values ≤ 1 with ~10²
  operations per fragment and up to ~10³ fragments composited per pixel gives errors
  ~10⁻⁵; 1e-4 is issue 3's bound.
- `s_delta`, 4 float32 ulps of the raster's largest coordinate, for "near a segment end".
- SLICE_DELTA = 1e-4 slice units for "near a slice boundary": depth relative error ~1e-7,
  times N/span.
- MAX_BAND = 1e-3: the share of pixels the camera band may hold (issue 3's bound).
"""

from __future__ import annotations

import numpy as np

from ._cache import cached
from ._constants import SHADOW_FILTER_RADIUS
from ._geometry._occluder import (
    interpolation_bound,
    occluder_hits,
    occluder_light_view,
    shadow_bias,
    silhouette_pixels,
)
from ._geometry._raster import Fragments, rasterize, ribbon_widths
from ._geometry._setup import prepare, visibility_order
from ._geometry._shadows import OpacityMaps, light_frame, with_receivers
from ._geometry._stage import geometry_stage
from ._scene._scene import Scene

__all__ = ["renderer_band", "camera_band", "shadow_band", "omega_uncertainty", "occluder_light_uncertainty",
           "transmittance_uncertainty", "PIXEL_TOL", "TAU_TOL", "SLICE_DELTA", "MAX_BAND"]

PIXEL_TOL = 1e-4
TAU_TOL = 1e-4
SLICE_DELTA = 1e-4
MAX_BAND = 1e-3
# A mesh occluder's pixel centres within this many pixels of an edge where its coverage
# jumps may fall on either side: llvmpipe rounds vertices to 1/256 pixel (8 sub-pixel
# bits) before its edge test, moving an edge by up to √2/512 ≈ 0.003 px (measured: an
# edge 0.001 px beyond a pixel centre still covers it in GL, one 0.002 px beyond does
# not); 4/256 is that with a 5× margin (no occluder pixel outside it differs on
# tests/test_occluder.py's scenes).
OCCLUDER_EDGE_DELTA = 4 / 256
# The same rounding moves each projected vertex by ≤ 1/512 px per axis, and GL's
# interpolated normal with it: inside triangles much smaller than a pixel by enough to
# matter (measured 1.1e-4 at one pixel of Sintel at 64²; JAX with vertices rounded to
# 1/256 differs from JAX by 2.3e-4 there, GL lies between). `interpolation_bound` bounds
# it to first order with that step; tests/test_occluder.py checks GL stays within it.
OCCLUDER_VERTEX_STEP = 1 / 512

# `_risk` per scene object: the geometry does not change with the shading parameters or
# colour_bound, so a fit's targets share one computation.


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


def s_delta(w: int, h: int) -> float:
    """4 float32 ulps of the raster's largest coordinate: GL projects points in float32,
    so screen coordinates carry about one ulp of error and s = (c − p₀)·u a few; 4 ulps is
    the measured envelope (at 2 ulps the default scene leaves unexplained pixels)."""
    return 4 * float(np.spacing(np.float32(max(w, h))))


def end_band(xy0, xy1, z0, z1, width, w, h, perspective) -> tuple[Fragments, np.ndarray]:
    """Fragments of the ribbons lengthened by δ = `s_delta` at both ends, and which of them
    lie within δ of an end (present lengthened, absent shortened by δ)."""
    delta = s_delta(w, h)
    d = xy1 - xy0
    u = d / np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-300)
    grow = rasterize(xy0 - delta * u, xy1 + delta * u, z0, z1, width, w, h, perspective)
    shrink = rasterize(xy0 + delta * u, xy1 - delta * u, z0, z1, width, w, h, perspective)
    key = lambda f: f.segment.astype(np.int64) * (w * h) + f.pixel  # noqa: E731
    return grow, ~np.isin(key(grow), key(shrink))


class _WindowSums:
    """Σ of fragment values over a point's (2k + 1)² filter texels and a range of keys:
    fragments keyed by `key(texel, level)` (increasing in both, a texel's keys below the
    next texel's), summed by prefix sums over the sorted keys."""

    def __init__(self, key, texel, level, values, resolution: int):
        order = np.argsort(key(texel, level), kind="stable")
        self.key, self.r = key, resolution
        self.keys = key(texel, level)[order]
        self.prefix = np.r_[0.0, np.cumsum(values[order])]

    def __call__(self, tx, ty, lo, hi) -> np.ndarray:
        """Per point at texel (tx, ty): Σ values with lo ≤ level ≤ hi in its filter's texels
        (texels outside the map hold nothing)."""
        k, r = SHADOW_FILTER_RADIUS, self.r
        total = np.zeros(np.shape(tx))
        for oy in range(-k, k + 1):
            for ox in range(-k, k + 1):
                nx, ny = tx + ox, ty + oy
                valid = (nx >= 0) & (nx < r) & (ny >= 0) & (ny < r)
                t = np.where(valid, ny * r + nx, 0)
                sums = (self.prefix[np.searchsorted(self.keys, self.key(t, hi), "right")]
                        - self.prefix[np.searchsorted(self.keys, self.key(t, lo), "left")])
                total += np.where(valid, sums, 0.0)
        return total / (2 * k + 1) ** 2


def omega_uncertainty(scene: Scene) -> np.ndarray:
    """Per point (`float[P]`), a bound on |Ω_GL − Ω_JAX| from light-side discontinuities
    within rounding (docs/model.md §7); 0 where none applies. All 0 for shadows "none".

    - A light-space fragment of opacity a = α·coverage within rounding of a segment end
      may be drawn or not; one within SLICE_DELTA of plane m may count towards plane m or
      not; for `exact`, one within 16 float32 ulps of a point's own depth may count as
      nearer or not. Each moves the Ω of a point whose (2k + 1)² filter reads its texel by
      at most a / (2k + 1)², and only where it can count at all: a fragment in slice j adds
      to planes j + 1 … N, so to points in slices ≥ j (opacity maps), or to points behind
      it (exact); moving across plane m changes plane m only, so points in slices m − 1
      and m.
    - A point within rounding of a texel edge may filter the neighbouring texels instead:
      it adds how much Ω differs there, the largest over the neighbours it may land in.
    - Points the light does not see (behind a point light) get no shadow in either: 0.
    """
    s = scene.strands
    if not scene.shadows.casts:
        return np.zeros(s.num_points)
    r = scene.shadows.resolution
    segs = s.segments()
    frame = light_frame(s.points, segs, s.width, scene.light, r, s.width_units)
    ids = frame.drawable
    a, b = segs[ids, 0], segs[ids, 1]
    xy, z = frame.xy, frame.depth
    width = ribbon_widths(s.width[s.strand_of_point[a]], s.width_units, z[a], z[b],
                          frame.view.focal, frame.view.perspective)
    frags, near_end = end_band(xy[a], xy[b], z[a], z[b], width, r, r, frame.view.perspective)
    opacity = _segment_opacity(scene)[ids[frags.segment]] * frags.coverage
    # Clipped before the cast: unseen points of a light at the hair's centre lie at ~1e300.
    tx = np.floor(np.clip(xy[:, 0], -1, r)).astype(np.int64)
    ty = np.floor(np.clip(xy[:, 1], -1, r)).astype(np.int64)

    if isinstance(scene.shadows, OpacityMaps):
        n = scene.shadows.maps
        u = frame.slice_coordinate(frags.depth, n)
        near_plane = np.abs(u - np.round(u)) < SLICE_DELTA
        u_point = frame.slice_coordinate(z, n)
        plane = np.clip(np.floor(u_point), 0, n - 1)  # the point's slice i, f its weight
        f = np.clip(u_point - plane, 0.0, 1.0)
        key = lambda texel, level: texel * (n + 2) + level  # noqa: E731  (levels 0 … N + 1)
        # A fragment in slice j adds to planes j + 1 … N: to a point in slice i fully for
        # j < i, with weight f for j = i. Near an end: slice j, or j − 1 if also near a plane.
        ends = _WindowSums(key, frags.pixel[near_end], np.clip(np.floor(u[near_end] - SLICE_DELTA), 0, n),
                           opacity[near_end], r)
        # Near plane m: to plane m only, weighted f in slice m − 1 and 1 − f in slice m.
        planes = _WindowSums(key, frags.pixel[near_plane], np.clip(np.round(u[near_plane]), 0, n),
                             opacity[near_plane], r)
        every = _WindowSums(key, frags.pixel, np.clip(np.floor(u), 0, n), opacity, r)

        def uncertain(x, y, i):
            i_, f_ = plane[i], f[i]
            return (ends(x, y, 0, i_ - 1) + f_ * ends(x, y, i_, i_)
                    + f_ * planes(x, y, i_ + 1, i_ + 1) + (1 - f_) * planes(x, y, i_, i_))

        def omega_at(x, y, i):
            # Ω̄(D_i) sums slices < i, Ω̄(D_{i+1}) slices ≤ i (slice N is dropped).
            return (1 - f[i]) * every(x, y, 0, plane[i] - 1) + f[i] * every(x, y, 0, plane[i])
    else:
        # Ω counts fragments strictly nearer than the point; depths within dz are ties.
        # 16 float32 ulps of the largest depth: GL's perspective-correct depths from a
        # point light were measured 5 ulps off (point_light.toml, exact, 128²).
        dz = 16 * float(np.spacing(np.float32(np.abs(z[frame.seen]).max(initial=0.0))))
        # One key per (texel, depth): the texel plus the depth mapped into [0, ½].
        def key(texel, depth):
            return texel + 0.5 * np.clip((depth - frame.zmin + 2 * dz) / (frame.span + 4 * dz), 0.0, 1.0)
        ends = _WindowSums(key, frags.pixel[near_end], frags.depth[near_end], opacity[near_end], r)
        every = _WindowSums(key, frags.pixel, frags.depth, opacity, r)

        def uncertain(x, y, i):
            return ends(x, y, -np.inf, z[i] + dz) + every(x, y, z[i] - dz, z[i] + dz)

        def omega_at(x, y, i):
            return every(x, y, -np.inf, z[i])

    everyone = np.arange(len(z))
    bound = uncertain(tx, ty, everyone)
    # A point within rounding of a texel edge may land in the neighbour (−1 or +1 per axis,
    # 0 where not near): GL's Ω then lies within that texel's bound of Ω there.
    frac = xy - np.floor(xy)
    side = np.where(frac < 1e-4, -1, np.where(1 - frac < 1e-4, 1, 0))
    edge = np.flatnonzero(frame.seen & (side != 0).any(axis=1))
    if edge.size:
        own = omega_at(tx[edge], ty[edge], edge)
        for sx, sy in ((1, 0), (0, 1), (1, 1)):
            x, y = tx[edge] + sx * side[edge, 0], ty[edge] + sy * side[edge, 1]
            there = uncertain(x, y, edge) + np.abs(omega_at(x, y, edge) - own)
            bound[edge] = np.maximum(bound[edge], there)
    bound[~frame.seen] = 0.0
    return bound


def shadow_band(scene: Scene) -> np.ndarray:
    """Points (`bool[P]`) whose Ω may depend on a light-side discontinuity within
    rounding (`omega_uncertainty` > 0). All False for shadows "none"."""
    return omega_uncertainty(scene) > 0


def transmittance_uncertainty(omega: np.ndarray, bound: np.ndarray) -> np.ndarray:
    """sup over κ > 0 of |exp(−κΩ) − exp(−κΩ')| for |Ω − Ω'| ≤ `bound`: how much τ may
    differ, whatever κ is (a fit does not know it). For a pair (a, a + d) the sup is at
    κ* = ln(1 + d/a)/d; for a given d it grows as a falls, so the worst pair lies below Ω
    (a = Ω − d). 1 where a ≤ 0 (κ → ∞ separates a shadow from none), 0 for d = 0, about
    d/(e·Ω) where d ≪ Ω."""
    d = np.asarray(bound, np.float64)
    a = np.asarray(omega, np.float64) - d
    out = np.ones_like(d)
    finite = np.isfinite(d) & (a > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        ka = np.where(finite, a * np.log1p(d / a) / d, 0.0)  # κ*·a
        kd = np.where(finite, np.log1p(d / a), 0.0)  # κ*·d
    out[finite] = (np.exp(-ka) * -np.expm1(-kd))[finite]
    out[d == 0] = 0.0
    return out


def occluder_light_uncertainty(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """(strand points `bool[P]`, pixels `bool[H·W]`) whose occluder light (docs/model.md
    §13) GL may compute differently within float32 rounding: V at a point within 1e-4 texel
    of a texel edge of the occluder's light raster, at a texel within OCCLUDER_EDGE_DELTA
    of the occluder's outline there, or within 1e-5 (relative) of the bias threshold; and
    at an occluder pixel, also Ω when its surface point lies within 1e-4 texel of an
    opacity-map texel edge or (opacity maps) SLICE_DELTA of a plane. Not covered: an
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
    frame = with_receivers(light_frame(s.points, s.segments(), s.width, scene.light, r, s.width_units),
                           surface)
    receiver = slice(s.num_points, None)
    unsure[receiver] |= near_edge(frame.xy[receiver])
    if isinstance(scene.shadows, OpacityMaps):
        u = frame.slice_coordinate(frame.depth[receiver], scene.shadows.maps)
        unsure[receiver] |= np.abs(u - np.round(u)) < SLICE_DELTA
    points_out[:] = unsure[:s.num_points]
    pixels_out[setup.occluder_pixel] = unsure[receiver]
    return points_out, pixels_out


def _risk(scene: Scene, shadows: bool) -> tuple[np.ndarray, np.ndarray]:
    """Per pixel (row-major): the summed weight α·T of fragments near a segment end, plus
    with `shadows` each other fragment's weight times how much its τ may differ (the larger
    of its ends' `transmittance_uncertainty`); and the pixels at the occluder's silhouette
    or depth (in the band whatever the colour). Cached per scene object (`_cache`)."""
    cache = cached(scene, "disagreement band", dict)
    if "camera" not in cache:
        cache.update(_camera_risk(scene))
    if shadows and "either" not in cache:
        cache["either"] = cache["camera"]
        cache["always_either"] = cache["always"]
        if scene.shadows.casts:
            # A fragment's colour mixes its segment's end colours, each moving by ≤ Δτ × its
            # fully lit colour: by ≤ max(Δτ₀, Δτ₁) × colour_bound.
            omega = np.asarray(geometry_stage(scene).omega, np.float64)
            dtau = transmittance_uncertainty(omega, omega_uncertainty(scene))
            if scene.occluder is not None:
                # §13: where GL's V or the occluder's Ω may differ, anything may.
                unsure_points, unsure_pixels = occluder_light_uncertainty(scene)
                dtau = np.where(unsure_points, 1.0, dtau)
                cache["always_either"] = cache["always"] | unsure_pixels
            i0, i1 = cache["ends"]
            risk = np.where(cache["near_end"], 0.0, np.maximum(dtau[i0], dtau[i1]))
            cache["either"] = cache["camera"] + np.bincount(cache["pixel"], cache["weights"] * risk,
                                                            minlength=cache["camera"].size)
    if shadows:
        return cache["either"], cache["always_either"]
    return cache["camera"], cache["always"]


def _segment_opacity(scene: Scene) -> np.ndarray:
    """Each segment's opacity: its strand's a, times the alpha texture of a Scheuermann
    scene (docs/model.md §17) — a smaller α in front lets more weight through behind."""
    s = scene.strands
    opacity = s.alpha[s.strand_of_point[s.segments()[:, 0]]]
    texture = prepare(scene).shading_inputs.segment_alpha
    return opacity if texture is None else opacity * texture


def _camera_risk(scene: Scene) -> dict:
    cam = scene.camera
    hw = cam.width * cam.height
    view, xy, depth, segments, order = visibility_order(scene)
    near_first = order[::-1]
    s0, s1 = segments[near_first, 0], segments[near_first, 1]
    strand = scene.strands.strand_of_point[s0]
    width = ribbon_widths(scene.strands.width[strand], scene.strands.width_units, depth[s0],
                          depth[s1], view.focal, view.perspective)
    frags, near_end = end_band(xy[s0], xy[s1], depth[s0], depth[s1], width, cam.width, cam.height, True)
    sort = np.argsort(frags.pixel, kind="stable")  # front to back within a pixel
    pixel = frags.pixel[sort]
    seg = frags.segment[sort]
    alpha = _segment_opacity(scene)[near_first[seg]] * frags.coverage[sort]
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
    return dict(camera=np.bincount(pixel, np.where(near_end, weights, 0.0), minlength=hw),
                always=always, pixel=pixel, weights=weights, near_end=near_end,
                ends=(s0[seg], s1[seg]))


def camera_band(scene: Scene, colour_bound: float) -> np.ndarray:
    """Pixels (`bool[H·W]`, row-major) a camera-side discontinuity within rounding can move
    by more than PIXEL_TOL, given the renderers' Ω are the same (as tests/test_gl.py's
    camera pass, which hands JAX's Ω to GL). See `renderer_band` for the bound."""
    camera, always = _risk(scene, shadows=False)
    return (camera * colour_bound > PIXEL_TOL) | always


def renderer_band(scene: Scene, colour_bound: float = 1.0) -> np.ndarray:
    """The pixels (`bool[H, W]`) where the JAX and GL renderers may differ by more than
    PIXEL_TOL (1e-4) because a discontinuity of the model lies within float32 rounding
    (docs/model.md §11), from the geometry alone: no render, no shading parameters.

    A camera fragment of compositing weight w = α·T (§6) can move its pixel by
    - w × `colour_bound` when the pixel centre lies within rounding of its segment's end
      (`end_band`): GL may draw it or not, and it replaces w of what lies behind it by its
      own colour;
    - otherwise w × Δτ × `colour_bound`, Δτ the larger `transmittance_uncertainty` of its
      segment's two end points, whose colours it mixes: GL's Ω at a point may differ by up
      to `omega_uncertainty`, τ = exp(−κΩ) then by up to Δτ whatever κ is, and the point's
      colour ambient·c + τ·light·(Kd·sin(T, L)·c + specular) by Δτ times its lit part.
    A pixel is in the band when these sum to more than PIXEL_TOL. Pixels at the occluder's
    silhouette (point-sampled, §9) or with hair at the sphere's own depth are in it
    whatever the colours. With shadows "none" only the first kind remains.

    `colour_bound`: a bound on the colours and on every point's fully lit colour; the
    image's brightest value is the practical stand-in (tests/test_gl.py and
    experiments/01_fit_recovery.py use it), 1 for images in [0, 1]. The sum is first order:
    weights as drawn, ignoring that a toggled fragment also changes T behind it. Because
    Δτ holds for every κ, a point whose Ω may differ taints every pixel of its two
    segments where they weigh enough, so the band holds more than MAX_BAND where shadows
    differ (2.7 % of the default scene at 224², docs/fitting.md); its camera part alone
    stays within MAX_BAND (tests/test_gl.py).

    The geometry, JAX's Ω (from `geometry_stage`, which needs no shading parameters)
    included, is cached per scene object: calling this for each target of a scene costs
    a comparison each.
    """
    either, always = _risk(scene, shadows=True)
    cam = scene.camera
    return ((either * colour_bound > PIXEL_TOL) | always).reshape(cam.height, cam.width)
