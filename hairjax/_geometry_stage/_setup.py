"""The geometry stage's set-up: everything that depends on geometry, camera and light
only (docs/model.md §2–§7, §13). NumPy and compiled loops on the host; on an accelerator
the rasters and the grouping by pixel run there as XLA programs (`_device_raster`).

Projection and the visibility order, the ribbons' fragments sorted front to back per
pixel, the occluder's test and its light, the shading model's per-point inputs, and the
shadow method's plan for Ω. A scene without shadows plans no shadow work; a scene
without occluder runs no occluder test. Cached per scene (`_cache`).
"""

from __future__ import annotations

import dataclasses
import time
import warnings
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from .._cache import cached
from .._errors import EmptyViewWarning
from .._geometry._capacity import fragment_bucket, refuses_out_of_memory
from .._geometry._device_raster import device_candidates, group_on_device
from .._geometry._group import group_parts
from .._geometry._host import release_heap, release_shared
from .._geometry._occluder import occluder_hits, occluder_light_view, occluder_visibility
from .._geometry._ordering import segment_depth
from .._geometry._placement import Placement, placement_of
from .._geometry._projection import View, camera_view
from .._geometry._raster import Arrays, rasterize_parts, ribbon_widths
from .._geometry._shadows import ShadowInputs
from .._scene._scene import Scene
from .._shading import PointInputs
from .._values._strands import tangents, unit_rows
from ._estimate import check_capacity

__all__ = ["GeometrySetup", "prepare", "visibility_order", "to_light", "warn_empty_view"]


@dataclasses.dataclass(frozen=True)
class GeometrySetup:
    """What the geometry stage needs that depends on neither opacity nor shading
    parameters (NumPy arrays; floats per point in JAX's default float precision)."""

    view: View
    tangent: np.ndarray  # [P, 3]
    to_light: np.ndarray  # [P, 3]
    to_eye: np.ndarray  # [P, 3]
    base_color: np.ndarray  # [P, 3] per-point colour (ones when the hair has none)
    light_rgb: np.ndarray  # [3]
    # Camera fragments, sorted by pixel, front to back within a pixel:
    # (NumPy from the host's loops, JAX arrays from a device's: `_device_raster`)
    frag_pixel: Arrays  # [F]
    frag_i0: Arrays  # [F] first point of the fragment's segment (the second is i0 + 1)
    frag_t: Arrays  # [F] screen-space position along the segment
    frag_coverage: Arrays  # [F]
    # The same four (pixel, i0, coverage, t), padded to `fragment_bucket(F)` entries of
    # pixel H·W and 0 (views of the same buffers on the host): what the geometry stage reads,
    # so that its programs compile once per bucket.
    padded_fragments: tuple[Arrays, Arrays, Arrays, Arrays]
    strand_of_point: np.ndarray  # [P] int32: a fragment's strand is strand_of_point[frag_i0]
    backdrop: np.ndarray  # [H*W, 3] the background behind the hair (0 on the occluder)
    opaque: np.ndarray  # [H*W] the occluder covers the pixel centre
    shadow: Any  # the shadow method's plan (None without shadows); with an
    #                              occluder, its surface points follow the strands'
    timings: dict
    shading_inputs: PointInputs  # the shading model's per-point inputs (§17's, or none)
    # The occluder (§9, §13); None without one:
    occluder_pixel: np.ndarray | None = None  # [Q] the pixels it covers
    occluder_direct: np.ndarray | None = None  # [Q, 3] k·light·max(N·L, 0) at them
    occluder_visibility: np.ndarray | None = None  # [Q] V there: 0 where it shadows itself
    occluder_color: np.ndarray | None = None  # [3] k
    light_visibility: np.ndarray | None = None  # [P] V: 0 where the occluder shadows a strand point

    # Derived where they are read, not stored: three more arrays per fragment would be
    # 0.31 GiB at 100k strands / 1024² (BENCHMARKS.md "Memory"). The geometry stage
    # derives them in JAX (`composite_weights`).
    @property
    def frag_strand(self) -> np.ndarray:
        """`[F]` int32: each fragment's strand."""
        return self.strand_of_point[self.frag_i0]

    @property
    def frag_first(self) -> np.ndarray:
        """`[F]` bool: the first fragment of its pixel."""
        first = np.ones(self.frag_pixel.size, bool)
        first[1:] = self.frag_pixel[1:] != self.frag_pixel[:-1]
        return first


@refuses_out_of_memory
def prepare(scene: Scene, *, order=None, placement: Placement | None = None) -> GeometrySetup:
    """The NumPy geometry set-up of `scene`, cached per scene object and placement (`_cache`).

    `order`: a draw order to use instead of the scene's (see `visibility_order`); such a
    set-up is computed afresh, not cached. `placement`: where the raster and the grouping
    run, "host" or "device" (`_placement`; None: `default_placement()`)."""
    where = placement_of(placement)
    # The set-up depends on concrete geometry only: evaluate it eagerly even when
    # `render` is being traced (e.g. under jax.jit or jax.grad).
    if order is not None:
        with jax.ensure_compile_time_eval():
            return _prepare(scene, order, where)

    def compute():
        with jax.ensure_compile_time_eval():
            return _prepare(scene, None, where)

    return cached(scene, f"setup on the {where}", compute)


def visibility_order(scene: Scene, order=None):
    """Camera projection and the segments' draw order (docs/model.md §2, §4), shared by
    the JAX and GL renderers.

    Returns `(view, xy [P, 2], depth [P], segments [E, 2], order)`; `order` lists the
    drawable segments (both ends beyond the near plane), the first drawn first.

    `order` (optional): segment indices, the first drawn first, to use instead of sorting
    for this camera — e.g. an order computed for an earlier view and reused (kim-2003 §3,
    Fig. 8). Segments in it that are not drawable from this camera are skipped; segments
    not in it are not drawn. Indices must be distinct and in [0, E).
    """
    cam = scene.camera
    view = camera_view(cam)
    xy, depth = view.project(scene.strands.points)
    segments = scene.strands.segments()
    # Segments with an end nearer than the near plane (or behind the eye) are not drawn.
    drawable_mask = (depth[segments[:, 0]] > cam.near) & (depth[segments[:, 1]] > cam.near)
    if order is not None:
        order = _given_order(order, len(segments))
        return view, xy, depth, segments, order[drawable_mask[order]]
    order = scene.ordering.order(
        scene.strands, segments, segment_depth(depth, segments), np.flatnonzero(drawable_mask)
    )
    return view, xy, depth, segments, order


def _given_order(order, n_segments: int) -> np.ndarray:
    """`order` checked: a 1-D array of distinct segment indices in [0, n_segments)."""
    order = np.asarray(order)
    if order.ndim != 1 or (order.size and not np.issubdtype(order.dtype, np.integer)):
        raise ValueError(
            f"order must be a 1-D array of segment indices, got shape {order.shape} and dtype {order.dtype}"
        )
    order = order.astype(np.int64)
    if order.size and (order.min() < 0 or order.max() >= n_segments):
        raise ValueError(f"order has segment indices outside [0, {n_segments})")
    if order.size and np.bincount(order, minlength=n_segments).max() > 1:
        raise ValueError("order lists a segment more than once")
    return order


def warn_empty_view(scene: Scene) -> None:
    """Warn (`EmptyViewWarning`) that `scene`'s hair covers no pixel, with the hair's
    bounding box and the camera, so that a black image does not come without a word."""
    cam, points = scene.camera, scene.strands.points

    def vec(v):
        return "(" + ", ".join(f"{x:.4g}" for x in v) + ")"

    warnings.warn(
        f"the hair covers no pixel of the {cam.width}x{cam.height} image: its bounding box is "
        f"{vec(points.min(axis=0))} .. {vec(points.max(axis=0))}, the camera's eye {vec(cam.eye)}, "
        f"target {vec(cam.target)}, fov {cam.fov:g} degrees; frame it with "
        'hairjax.experimental.frame_camera(strands) or [camera] frame = "auto"',
        EmptyViewWarning,
        stacklevel=2,
    )


def to_light(light, points: np.ndarray) -> np.ndarray:
    """Unit vectors from `points` to the light (`[P, 3]`; 0 at a point light's position)."""
    if light.kind == "directional":
        d = -np.asarray(light.direction, dtype=np.float64)
        return np.broadcast_to(d / np.linalg.norm(d), points.shape)
    return unit_rows(np.asarray(light.position, dtype=np.float64) - points)


def _prepare(scene: Scene, order, placement: Placement) -> GeometrySetup:
    release_shared()  # a forgotten scene's fragments, before this one's are allocated
    timings: dict[str, float] = {}
    clock = time.perf_counter()

    def lap(name):
        nonlocal clock
        now = time.perf_counter()
        timings[name] = timings.get(name, 0.0) + now - clock  # a stage may run in parts
        clock = now

    strands, cam = scene.strands, scene.camera
    points = strands.points
    check_capacity(scene, placement=placement)  # the closed-form items, before anything is projected
    view, xy, depth, segments, order = visibility_order(scene, order)
    seg_strand = strands.strand_of_point[segments[:, 0]]
    lap("project+order")

    tangent = tangents(points, strands.offsets)
    base_color = strands.color if strands.color is not None else np.ones_like(points)
    inputs = scene.shading.point_inputs(strands, tangent)  # the model's own (§17's), or none
    if inputs.color_factor is not None:
        base_color = base_color * inputs.color_factor
    segment_alpha = inputs.segment_alpha
    if any(x is not None for x in (inputs.extra, inputs.color_factor, inputs.segment_alpha)):
        lap("shading inputs")

    # Rasterise nearest-first, then a stable sort by pixel gives front-to-back per pixel.
    near_first = order[::-1]
    s0, s1 = segments[near_first, 0], segments[near_first, 1]
    widths = ribbon_widths(
        strands.width[seg_strand[near_first]],
        strands.width_units,
        depth[s0],
        depth[s1],
        view.focal,
        view.perspective,
    )
    # Rasterised nearest segment first; each fragment names its segment's first point
    # (the segment is that point and the next). Depth only for the occluder's depth test.
    raster = (xy[s0], xy[s1], depth[s0], depth[s1], widths, cam.width, cam.height, True)
    # With the fragments, before the image's arrays and theirs.
    check_capacity(scene, raster, placement=placement)
    lap("capacity")
    hw = cam.width * cam.height
    light = scene.light
    light_rgb = np.asarray(light.color, dtype=np.float64)
    backdrop = np.broadcast_to(np.asarray(scene.background, np.float64), (hw, 3)).copy()
    opaque = np.zeros(hw, bool)
    occluder = {}
    hit_depth = None
    if scene.occluder is not None:
        hit_depth, normal, hit_point = occluder_hits(view, scene.occluder)
        opaque = np.isfinite(hit_depth)
        occ_pixel = np.flatnonzero(opaque)
        surface = hit_point[occ_pixel]
        to_l = to_light(light, surface)
        # Lambert's max(N·L, 0) (§9): the clip fires on the occluder's unlit side.
        lambert = np.clip(np.sum(normal[occ_pixel] * to_l, axis=1), 0.0, None)
        color = np.asarray(scene.occluder.color, np.float64)
        occluder = dict(
            occluder_pixel=occ_pixel,
            occluder_color=color,
            occluder_direct=color * light_rgb * lambert[:, None],
        )
        backdrop[opaque] = 0.0  # the shading stage adds the occluder's colour (§13)
        lap("occluder")

    place = _fragments_on_device if placement == "device" else _fragments_on_host
    drawn, padded, n_frags = place(raster, s0.astype(np.int32), hit_depth, lap)
    frag_pixel, frag_i0, frag_coverage, frag_t = padded
    # Hair whose segments all have length 0 (or that has none: one-point strands) draws
    # nothing from any camera; that is not the camera's fault, so no warning then.
    if not drawn and np.any(points[segments[:, 0]] != points[segments[:, 1]]):
        warn_empty_view(scene)
    if segment_alpha is not None:  # §17's alpha texture scales the segment's opacity
        at_first_point = np.zeros(points.shape[0], segment_alpha.dtype)
        at_first_point[segments[:, 0]] = segment_alpha
        if isinstance(frag_coverage, jax.Array):  # on the device, in the fragments' precision
            frag_coverage = frag_coverage * jnp.asarray(at_first_point, frag_coverage.dtype)[frag_i0]
            padded = (frag_pixel, frag_i0, frag_coverage, frag_t)
        else:  # in place: the exact views below see it (padding: coverage 0 stays 0)
            frag_coverage *= at_first_point[frag_i0]

    shadow = None
    if scene.shadows.casts:
        receivers = surface if occluder else None
        shadow_inputs = ShadowInputs(
            points,
            segments,
            seg_strand,
            strands.width,
            light,
            receivers=receivers,
            segment_alpha=segment_alpha,
            width_units=strands.width_units,
            placement=placement,
        )
        shadow = scene.shadows.setup(shadow_inputs)
        lap("shadow set-up")
        if occluder:
            # §13: the occluder's shadow, a depth test in the light's view.
            light_view = occluder_light_view(light, points, scene.occluder, scene.shadows.resolution)
            depth_map, _, _ = occluder_hits(light_view, scene.occluder)
            occluder["light_visibility"] = occluder_visibility(light_view, depth_map, points)
            occluder["occluder_visibility"] = occluder_visibility(light_view, depth_map, surface)
            lap("occluder shadow")
    if shadow is not None:  # the shadow set-up's transients, trimmed for a scene this large
        release_heap(frag_pixel.size * 20)

    # The per-point inputs in the stage's float precision: it reads nothing else of them.
    dtype = jnp.result_type(float)
    return GeometrySetup(
        view=view,
        tangent=tangent.astype(dtype),
        to_light=to_light(light, points).astype(dtype),
        to_eye=unit_rows(view.origin - points).astype(dtype),
        base_color=base_color.astype(dtype),
        light_rgb=light_rgb,
        frag_pixel=frag_pixel[:n_frags],
        frag_i0=frag_i0[:n_frags],
        frag_t=frag_t[:n_frags],
        frag_coverage=frag_coverage[:n_frags],
        padded_fragments=padded,
        strand_of_point=strands.strand_of_point.astype(np.int32),
        backdrop=backdrop,
        opaque=opaque,
        shadow=shadow,
        timings=timings,
        shading_inputs=inputs,
        **occluder,
    )


def _fragments_on_host(raster, labels, hit_depth, lap):
    """Whether the raster covered any pixel (before the occluder's depth test), the
    camera's fragments grouped by pixel, front to back (`frag_pixel`, `frag_i0`,
    `frag_coverage`, `frag_t`, padded to `fragment_bucket`), and their count, by the host's
    compiled loops: the raster in pieces, one per core (`rasterize_parts`), read where they
    are by the counting sort (`group_parts`), into aligned arrays that the geometry stage
    shares with JAX (`_host`)."""
    with_depth = hit_depth is not None
    pieces = rasterize_parts(*raster, depth=with_depth, labels=labels)
    n_frags = sum(piece.size for piece in pieces)
    lap("rasterize")
    if with_depth:  # kim-2003 §3: depth test on, hair does not write depth.
        pieces = [piece.take(np.flatnonzero(piece.depths < hit_depth[piece.pixel])) for piece in pieces]
        lap("occluder")
    # Only what compositing needs is grouped: segment, coverage, t (not depth).
    count = sum(piece.size for piece in pieces)
    padded = group_parts(
        [(piece.pixel, piece.segment, piece.coverage, piece.t) for piece in pieces],
        raster[5] * raster[6],
        fragment_bucket(count),
    )
    del pieces
    release_heap(n_frags * 16)  # the raster's 4 fields, handed back to the system
    lap("sort fragments")
    return n_frags > 0, (padded[0], *padded[1]), count


def _fragments_on_device(raster, labels, hit_depth, lap):
    """`_fragments_on_host`'s fragments as XLA programs on JAX's default device
    (`_device_raster`): every candidate of the same raster plan, then one stable sort by
    pixel that also drops the uncovered and occluded candidates. JAX arrays."""
    candidates = device_candidates(*raster, depth=hit_depth is not None, labels=labels)
    keep = candidates.coverage > 0
    jax.block_until_ready(keep)  # the lap times the raster, not its dispatch
    lap("rasterize")
    if hit_depth is not None:  # kim-2003 §3: depth test on, hair does not write depth.
        dtype = candidates.depths.dtype
        # d < h for a float64 h is d < h↑, h rounded up to the next float of d's type, so
        # the test in that type is the host's (which compares in float64).
        bound = hit_depth.astype(dtype)
        bound = np.where(bound < hit_depth, np.nextafter(bound, np.inf, dtype=dtype), bound)
        # clip: an uncovered candidate's pixel may lie outside the image; it is dropped anyway.
        keep &= candidates.depths < jnp.asarray(bound)[jnp.clip(candidates.pixel, 0, bound.size - 1)]
    hw = raster[5] * raster[6]
    frag_pixel, grouped, count = group_on_device(
        candidates.pixel,
        keep,
        hw,
        candidates.segment,
        candidates.coverage,
        candidates.t,
        capacity=fragment_bucket,
    )
    lap("sort fragments")
    # Covered before the depth test: read back only when nothing is left after it.
    drawn = count > 0 or bool(jnp.any(candidates.coverage > 0))
    return drawn, (frag_pixel, *grouped), count
