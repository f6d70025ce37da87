"""The geometry stage's set-up: everything that depends on geometry, camera and light
only (docs/model.md §2–§7, §13). NumPy and compiled loops on the host; on an accelerator
the rasters and the grouping by pixel run there as XLA programs (`_device_raster`).

`_prepare` runs its steps in turn, each handing the next a named record: projection and
the visibility order (`visibility_order`, `VisibleSegments`), the shading model's
per-point inputs (`_point_shading`), the camera's ribbons nearest first (`_camera_raster`,
a `RibbonRaster`), the occluder seen from the camera and its light (`_lighting`), the
camera's fragments grouped by pixel front to back (`_fragments`), the shadow method's
plan for Ω with the occluder's own shadow (`_lighting`), and the `GeometrySetup` they
make (`_geometry_setup`). A scene without shadows plans no shadow work; a scene without
occluder runs no occluder test. Cached per scene (`_cache`).
"""

from __future__ import annotations

import dataclasses
import warnings
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from .._cache import cached
from .._errors import EmptyViewWarning
from .._geometry._capacity import refuses_out_of_memory
from .._geometry._hidden import drawn_cutoff
from .._geometry._host import release_heap, release_shared
from .._geometry._ordering import segment_depth
from .._geometry._placement import Placement, placement_of
from .._geometry._projection import View, camera_view
from .._geometry._raster import Arrays
from .._geometry._raster_plan import RibbonRaster, ribbon_widths
from .._geometry._seen import SETUP_MARGIN, Seen
from .._laps import Laps
from .._scene._scene import Scene
from .._shading import PointInputs
from .._values._strands import tangents, unit_rows
from ._estimate import check_capacity, scene_light_raster
from ._fragments import CameraFragments, PaddedFragments, camera_fragments
from ._lighting import OccluderView, ShadowPlan, occluder_view, shadow_plan, to_light

__all__ = [
    "GeometrySetup",
    "VisibleSegments",
    "prepare",
    "render_cutoff",
    "visibility_order",
    "to_light",
    "warn_empty_view",
]


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
    padded_fragments: PaddedFragments
    strand_of_point: np.ndarray  # [P] int32: a fragment's strand is strand_of_point[frag_i0]
    backdrop: np.ndarray  # [H*W, 3] the background behind the hair (0 on the occluder)
    opaque: np.ndarray  # [H*W] the occluder covers the pixel centre
    # [H*W] each pixel's product of (1 − α) over the hidden fragments the set-up left out
    # (`_seen`), which its transmittance keeps; None when it kept every fragment
    hidden: Arrays | None
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
def prepare(
    scene: Scene, *, order=None, placement: Placement | None = None, cutoff: float = 0.0
) -> GeometrySetup:
    """The NumPy geometry set-up of `scene`, cached per scene object, placement and cutoff
    (`_cache`).

    `order`: a draw order to use instead of the scene's (see `visibility_order`); such a
    set-up is computed afresh, not cached. `placement`: where the raster and the grouping
    run, "host" or "device" (`_placement`; None: `default_placement()`). `cutoff`: leave
    out the camera fragments seen, at the scene's strand opacities, through a
    transmittance below it (`_seen`; a render's is `render_cutoff()`); 0, the default,
    keeps every one, as a traced opacity needs."""
    where = placement_of(placement)
    cutoff = float(cutoff)
    # The set-up depends on concrete geometry only: evaluate it eagerly even when
    # `render` is being traced (e.g. under jax.jit or jax.grad).
    if order is not None:
        with jax.ensure_compile_time_eval():
            return _prepare(scene, order, where, cutoff)

    def compute():
        with jax.ensure_compile_time_eval():
            return _prepare(scene, None, where, cutoff)

    key = f"setup on the {where}" + (f", cutoff {cutoff!r}" if cutoff > 0 else "")
    return cached(scene, key, compute)


def render_cutoff(stage_cutoff: float | None = None) -> float:
    """The set-up's cutoff for a geometry stage that leaves out the fragments hidden at
    `stage_cutoff` (None: `drawn_cutoff` of the working precision; 0: none): SETUP_MARGIN
    times it, and never above the drawn cutoff's, so that every positive cutoff shares one
    set-up (`_seen`)."""
    drawn = drawn_cutoff(jnp.result_type(float))
    stage_cutoff = drawn if stage_cutoff is None else float(stage_cutoff)
    return SETUP_MARGIN * min(stage_cutoff, drawn)


class VisibleSegments(NamedTuple):
    """The camera's `view`, the strand points projected by it (`xy`, `[P, 2]` pixel
    coordinates; `depth`, `[P]`), the `segments` (`[E, 2]` point indices) and their draw
    `order`: the drawable segments (both ends beyond the near plane), the first drawn first."""

    view: View
    xy: np.ndarray
    depth: np.ndarray
    segments: np.ndarray
    order: np.ndarray


def visibility_order(scene: Scene, order=None) -> VisibleSegments:
    """Camera projection and the segments' draw order (docs/model.md §2, §4), shared by
    the JAX and GL renderers (`VisibleSegments`, which unpacks as `(view, xy, depth,
    segments, order)`).

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
        return VisibleSegments(
            view=view, xy=xy, depth=depth, segments=segments, order=order[drawable_mask[order]]
        )
    order = scene.ordering.order(
        scene.strands, segments, segment_depth(depth, segments), np.flatnonzero(drawable_mask)
    )
    return VisibleSegments(view=view, xy=xy, depth=depth, segments=segments, order=order)


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


@dataclasses.dataclass(frozen=True)
class _PointShading:
    """The shading model's per-point inputs (§17's, or none) and what follows from them:
    the unit `tangent` and the per-point `base_color` (the strands' colour, ones when the
    hair has none, times the model's colour factor), `[P, 3]` float64 each."""

    tangent: np.ndarray
    base_color: np.ndarray
    inputs: PointInputs


class _CameraRaster(NamedTuple):
    """The camera's raster, nearest segment first (`raster`), and each segment's first
    point (`labels`, `[E]` int32), which its fragments name (the segment is that point and
    the next)."""

    raster: RibbonRaster
    labels: np.ndarray


def _prepare(scene: Scene, order, placement: Placement, cutoff: float) -> GeometrySetup:
    """`prepare`'s set-up, computed: its steps in order, each timed (`GeometrySetup.timings`)."""
    release_shared()  # a forgotten scene's fragments, before this one's are allocated
    lap = Laps()
    check_capacity(scene, placement=placement)  # the closed-form items, before anything is projected
    visible = visibility_order(scene, order)
    seg_strand = scene.strands.strand_of_point[visible.segments[:, 0]]
    lap("project+order")
    shading = _point_shading(scene, lap)
    camera = _camera_raster(scene, visible, seg_strand)
    light = scene_light_raster(scene)  # made once, for the estimate and the shadow method
    # With the fragments, before the image's arrays and theirs.
    check_capacity(scene, camera.raster, light=light, placement=placement)
    lap("capacity")
    occluder = (
        None if scene.occluder is None else occluder_view(scene.occluder, scene.light, visible.view, lap)
    )
    seen = Seen(
        hit=None if occluder is None else occluder.hit_depth,
        opacity=None if cutoff <= 0 else _label_opacity(scene, shading.inputs, visible.segments),
        cutoff=cutoff,
    )
    fragments = camera_fragments(camera.raster, camera.labels, seen, placement, lap)
    # Hair whose segments all have length 0 (or that has none: one-point strands) draws
    # nothing from any camera; that is not the camera's fault, so no warning then.
    points, segments = scene.strands.points, visible.segments
    if not fragments.drawn and np.any(points[segments[:, 0]] != points[segments[:, 1]]):
        warn_empty_view(scene)
    padded = _with_segment_alpha(fragments.padded, shading.inputs.segment_alpha, points.shape[0], segments)
    # A cut set-up serves the scene's own opacities only (`_seen`): so may its shadow plan.
    opacity = scene.strands.alpha if cutoff > 0 else None
    shadows = shadow_plan(
        scene, segments, seg_strand, shading.inputs.segment_alpha, occluder, placement, lap, light, opacity
    )
    if shadows.plan is not None:  # the shadow set-up's transients, trimmed for a scene this large
        release_heap(padded.pixel.size * 20)
    return _geometry_setup(scene, visible.view, shading, padded, fragments, occluder, shadows, lap)


def _label_opacity(scene: Scene, inputs: PointInputs, segments: np.ndarray) -> np.ndarray:
    """`[P]` float64: the opacity of the segment each point starts, its strand's α times
    the segment's alpha texture (§17's; none: 1), as the geometry stage weighs its
    fragments (`fragment_alpha`, `_with_segment_alpha`)."""
    opacity = np.asarray(scene.strands.alpha, np.float64)[scene.strands.strand_of_point]
    if inputs.segment_alpha is not None:
        opacity[segments[:, 0]] *= inputs.segment_alpha
    return opacity


def _point_shading(scene: Scene, lap: Laps) -> _PointShading:
    """The strands' tangents, the shading model's per-point inputs and the base colour."""
    strands = scene.strands
    tangent = tangents(strands.points, strands.offsets)
    base_color = strands.color if strands.color is not None else np.ones_like(strands.points)
    inputs = scene.shading.point_inputs(strands, tangent)  # the model's own (§17's), or none
    if inputs.color_factor is not None:
        base_color = base_color * inputs.color_factor
    if any(x is not None for x in (inputs.extra, inputs.color_factor, inputs.segment_alpha)):
        lap("shading inputs")
    return _PointShading(tangent=tangent, base_color=base_color, inputs=inputs)


def _camera_raster(scene: Scene, visible: VisibleSegments, seg_strand: np.ndarray) -> _CameraRaster:
    """The drawn segments' ribbons in the camera's pixels (§5), nearest first: a stable
    sort of their fragments by pixel then leaves each pixel's front to back (§6). Depth is
    interpolated for the occluder's depth test only."""
    near_first = visible.order[::-1]
    s0 = visible.segments[near_first, 0]
    view, strands = visible.view, scene.strands
    # A segment joins consecutive points (`Strands.segments`), so each point's (x, y, depth)
    # and its successor's are six consecutive floats of `ends`: one gather of them per
    # segment, where the segments in draw order are far apart, instead of one per end and
    # field (six of 1.5 M random reads took 0.3–0.4 s at 100k strands, this one 0.1 s).
    ends = np.column_stack([visible.xy, visible.depth]).reshape(-1)
    both = ends[(3 * s0)[:, None] + np.arange(6)]  # [E, 6]: x₀, y₀, z₀, x₁, y₁, z₁
    z0, z1 = both[:, 2], both[:, 5]
    widths = ribbon_widths(
        strands.width[seg_strand[near_first]], strands.width_units, z0, z1, view.focal, view.perspective
    )
    raster = RibbonRaster(
        xy0=both[:, 0:2],
        xy1=both[:, 3:5],
        z0=z0,
        z1=z1,
        width=widths,
        image_width=view.width,
        image_height=view.height,
        perspective=view.perspective,
    )
    return _CameraRaster(raster=raster, labels=s0.astype(np.int32))


def _with_segment_alpha(
    padded: PaddedFragments, segment_alpha: np.ndarray | None, n_points: int, segments: np.ndarray
) -> PaddedFragments:
    """`padded` with each fragment's coverage scaled by its segment's alpha (§17's alpha
    texture; None: unscaled)."""
    if segment_alpha is None:
        return padded
    at_first_point = np.zeros(n_points, segment_alpha.dtype)
    at_first_point[segments[:, 0]] = segment_alpha
    if isinstance(padded.coverage, jax.Array):  # on the device, in the fragments' precision
        scale = jnp.asarray(at_first_point, padded.coverage.dtype)[padded.i0]
        return padded._replace(coverage=padded.coverage * scale)
    # In place on the host: the exact views of `GeometrySetup` see it (padding: 0 stays 0).
    coverage = padded.coverage
    coverage *= at_first_point[padded.i0]
    return padded


def _geometry_setup(
    scene: Scene,
    view: View,
    shading: _PointShading,
    padded: PaddedFragments,
    fragments: CameraFragments,
    occluder: OccluderView | None,
    shadows: ShadowPlan,
    lap: Laps,
) -> GeometrySetup:
    """The steps' results as the geometry stage reads them: the per-point inputs in its
    float precision (it reads nothing else of them), the image's backdrop and the
    occluder's pixels."""
    points, light = scene.strands.points, scene.light
    hw = view.width * view.height
    backdrop = np.broadcast_to(np.asarray(scene.background, np.float64), (hw, 3)).copy()
    opaque = np.zeros(hw, bool) if occluder is None else occluder.opaque
    backdrop[opaque] = 0.0  # the shading stage adds the occluder's colour (§13)
    dtype = jnp.result_type(float)
    count = fragments.count
    return GeometrySetup(
        view=view,
        tangent=shading.tangent.astype(dtype),
        to_light=to_light(light, points).astype(dtype),
        to_eye=unit_rows(view.origin - points).astype(dtype),
        base_color=shading.base_color.astype(dtype),
        light_rgb=np.asarray(light.color, dtype=np.float64),
        frag_pixel=padded.pixel[:count],
        frag_i0=padded.i0[:count],
        frag_t=padded.t[:count],
        frag_coverage=padded.coverage[:count],
        padded_fragments=padded,
        strand_of_point=scene.strands.strand_of_point.astype(np.int32),
        backdrop=backdrop,
        opaque=opaque,
        hidden=fragments.hidden,
        shadow=shadows.plan,
        timings=lap.timings,
        shading_inputs=shading.inputs,
        occluder_pixel=None if occluder is None else occluder.pixel,
        occluder_direct=None if occluder is None else occluder.direct,
        occluder_visibility=shadows.occluder_visibility,
        occluder_color=None if occluder is None else occluder.color,
        light_visibility=shadows.light_visibility,
    )
