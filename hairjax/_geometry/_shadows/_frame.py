"""The light's view of the hair, shared by every shadow method and by both renderers
(kim-2003 §4, docs/model.md §7): the light's raster and depth range (`LightFrame`), the
ribbons rasterised from the light, and the receivers' texels (`LightFragments`).
"""

from __future__ import annotations

import dataclasses
import functools
from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from ..._constants import PIXEL_HALF_EXTENT, SHADOW_FILTER_RADIUS
from .._device_raster import rasterize_on_device
from .._placement import Placement
from .._projection import View, light_view
from .._raster import Arrays, Fragments, joined, rasterize_parts
from .._raster_plan import RibbonRaster, ribbon_widths

__all__ = [
    "ShadowInputs",
    "LightFrame",
    "light_frame",
    "light_raster",
    "with_receivers",
    "map_margin",
    "LightFragments",
    "light_fragments",
]


class ShadowInputs(NamedTuple):
    """What a shadow method plans Ω from (`AbstractShadowMethod.setup`): the geometry
    and, for a render, the opacities it is planned for (docs/model.md §7).

    - `points` `[P, 3]`, `segments` `[E, 2]` (point indices), `seg_strand` `[E]` (each
      segment's strand), `width` `[S]` (per strand, in `width_units`: "pixels" or "world");
    - `light`: the scene's `Light`;
    - `receivers` `[Q, 3]`: more points Ω is wanted at (the occluder's surface, §13): the
      per-point results get P + Q entries;
    - `segment_alpha` `[E]`: a factor on each segment's opacity (the alpha texture, §17);
    - `placement`: where the light's raster runs, for a method that can run it on the
      device (`rasterizes_on_device`; `_placement`);
    - `raster`: the light's frame and raster (`light_raster` of these inputs at the
      method's resolution) where the set-up has made them already, for its capacity
      estimate; None: made here;
    - `opacity` `[S]`: the strand opacities Ω is wanted at, where they are known when it
      is planned (a render's set-up: the scene's α). A method may then fold them into its
      plan, which serves those opacities only. None: a plan for any α (a traced one)."""

    points: np.ndarray
    segments: np.ndarray
    seg_strand: np.ndarray
    width: np.ndarray
    light: object
    receivers: np.ndarray | None = None
    segment_alpha: np.ndarray | None = None
    width_units: str = "pixels"
    placement: Placement = "host"
    raster: tuple | None = None
    opacity: np.ndarray | None = None


def map_margin(width: np.ndarray) -> int:
    """Texels kept free at the map border: the widest ribbon's reach plus the filter."""
    # initial=1.0 fires only without strands (empty width): the margin of width 1.
    return int(np.ceil(0.5 * float(np.max(width, initial=1.0)) + PIXEL_HALF_EXTENT)) + SHADOW_FILTER_RADIUS


def _world_width_view(view: View, light, points, width, resolution: int) -> View:
    """The light's view with a margin for ribbons `width` world units wide (§7).

    Their width in texels depends on the view's scale, which depends on the margin: the
    view framed with the pixel-width margin gives texel widths, and the margin is widened
    to them. A wider margin only lowers the scale (fewer usable texels over the same
    extent or angle), so the ribbons are then no wider than the new margin allows for."""
    _, depth = view.project(points)
    seen = depth > view.near if view.perspective else np.ones(len(points), bool)
    scale = view.focal / depth[seen] if view.perspective else np.full(int(seen.sum()), view.focal)
    texels = float(np.max(width, initial=0.0)) * scale  # an upper bound per point: the widest strand
    margin = map_margin(texels)
    if 2 * margin >= resolution:
        raise ValueError(
            f"ribbons {float(np.max(width)):g} world units wide are up to "
            f"{float(np.max(texels, initial=0.0)):.3g} texels wide in the light's "
            f"{resolution}² view: too wide for its border; use a higher "
            "shadows.resolution or a smaller hair.width"
        )
    return light_view(light, points, resolution, margin)


@dataclasses.dataclass(frozen=True)
class LightFrame:
    """The light's raster and depth range, shared by the JAX and GL renderers.

    `xy`, `depth`: every point in the light's view; `seen`: points in front of a point
    light (all, for a directional one); `drawable`: segments with both ends seen;
    slices are measured from `zmin` over `span` (D₀ and D_N − D₀ of docs/model.md §7).
    """

    view: View
    xy: np.ndarray
    depth: np.ndarray
    seen: np.ndarray
    drawable: np.ndarray
    zmin: float
    span: float

    def slice_coordinate(self, z: Arrays, maps: int) -> Arrays:
        """(z − D₀)·N/span: exactly N at z = D_N, so the farthest points' own fragments
        never count as nearer than the last plane."""
        return (z - self.zmin) * maps / self.span


def light_frame(points, segments, width, light, resolution: int, width_units: str = "pixels") -> LightFrame:
    """The light's view (docs/model.md §7) of strands of per-strand `width` (`[S]` or, in
    pixels, any array whose max matters) in `width_units`."""
    view = light_view(light, points, resolution, map_margin(width))
    if width_units == "world":
        view = _world_width_view(view, light, points, width, resolution)
    xy, depth = view.project(points)
    seen = np.ones(len(points), bool)
    if view.perspective:
        # Point light: points behind its near plane get no shadow and cast none.
        seen = depth > view.near
    drawable = np.flatnonzero(seen[segments[:, 0]] & seen[segments[:, 1]])
    # The else fires when no point is in front of a point light: nothing casts or gets shadow.
    zmin = float(depth[seen].min()) if seen.any() else 0.0
    zmax = float(depth[seen].max()) if seen.any() else 0.0
    span = zmax - zmin
    # Fires when every point is at one depth from the light: nothing is strictly nearer
    # than any plane, and any positive spacing gives that Ω = 0.
    span = span if span > 0 else 1.0
    return LightFrame(view, xy, depth, seen, drawable, zmin, span)


def with_receivers(frame: LightFrame, receivers: np.ndarray | None) -> LightFrame:
    """`frame` with `receivers` (`[Q, 3]`, e.g. the occluder's visible surface points,
    docs/model.md §13) appended to its points: they get Ω like strand points but neither
    cast nor move the depth range D₀ … D_N. Unchanged for None."""
    if receivers is None:
        return frame
    xy, depth = frame.view.project(receivers)
    # Behind a point light's near plane: no shadow, as for strand points.
    seen = depth > frame.view.near if frame.view.perspective else np.ones(len(depth), bool)
    return dataclasses.replace(
        frame,
        xy=np.concatenate([frame.xy, xy]),
        depth=np.concatenate([frame.depth, depth]),
        seen=np.concatenate([frame.seen, seen]),
    )


@dataclasses.dataclass(frozen=True)
class LightFragments:
    """The strands rasterised from the light, with the points that receive shadow.

    `frame`: the light's frame with the receivers appended to its points; `pieces`: the
    light-space fragments (`_raster.Fragments`, `segment` indexing the drawn segments) as
    the raster wrote them, in pieces that in order are all of them; per drawn segment its
    strand `segment_strand` and the alpha texture's factor `segment_factor` (§17; None
    without); per receiving point its texel `tx`, `ty` and `inside` (seen and on the map).
    `frags` (the pieces joined in place: read no piece after it), `frag_strand[F]` and
    `frag_coverage[F]` (times the factor) are made on first use: a plan that sums the
    fragments on the host reads the pieces and the tables instead."""

    frame: LightFrame
    pieces: list[Fragments]
    segment_strand: Arrays
    segment_factor: Arrays | None
    tx: np.ndarray
    ty: np.ndarray
    inside: np.ndarray

    @property
    def count(self) -> int:
        """The number of fragments."""
        return sum(int(piece.pixel.shape[0]) for piece in self.pieces)

    @functools.cached_property
    def frags(self) -> Fragments:
        return self.pieces[0] if len(self.pieces) == 1 else joined(self.pieces)

    @functools.cached_property
    def frag_strand(self) -> Arrays:
        return self.segment_strand[self.frags.segment]

    @functools.cached_property
    def frag_coverage(self) -> Arrays:
        coverage = self.frags.coverage
        return coverage if self.segment_factor is None else coverage * self.segment_factor[self.frags.segment]


def light_raster(points, segments, seg_strand, width, light, resolution: int, width_units: str = "pixels"):
    """The light's frame and its raster's arguments (a `RibbonRaster`): the
    drawable segments' ends in the light's view and their ribbons' widths in texels
    (the strand's width in pixels, or its world width seen from the light,
    `ribbon_widths`). Shared by `light_fragments` and the capacity estimate."""
    frame = light_frame(points, segments, width, light, resolution, width_units)
    seg_ids = frame.drawable
    s0, s1 = segments[seg_ids, 0], segments[seg_ids, 1]
    widths = ribbon_widths(
        width[seg_strand[seg_ids]],
        width_units,
        frame.depth[s0],
        frame.depth[s1],
        frame.view.focal,
        frame.view.perspective,
    )
    xy, depth = frame.xy, frame.depth
    return frame, RibbonRaster(
        xy0=xy[s0],
        xy1=xy[s1],
        z0=depth[s0],
        z1=depth[s1],
        width=widths,
        image_width=resolution,
        image_height=resolution,
        perspective=frame.view.perspective,
    )


def light_fragments(inputs: ShadowInputs, resolution: int, *, on_device: bool = False) -> LightFragments:
    """Rasterise `inputs`' strands from the light (same ribbons as the camera pass; width in
    texels = the strand's width in pixels, or its world width seen from the light,
    `ribbon_widths`) on a `resolution`² raster, then find the texel of every point and of
    every receiver (the per-point arrays get P + Q entries), with the segments' alpha
    texture applied. `on_device`: rasterise as an XLA program on JAX's default device
    (`_device_raster`): the fragments are then JAX arrays there, the per-point arrays
    NumPy still."""
    seg_strand = inputs.seg_strand
    frame, raster = inputs.raster or light_raster(
        inputs.points, inputs.segments, seg_strand, inputs.width, inputs.light, resolution, inputs.width_units
    )
    seg_ids = frame.drawable
    pieces = [rasterize_on_device(*raster)] if on_device else rasterize_parts(*raster)
    frame = with_receivers(frame, inputs.receivers)
    xy, seen = frame.xy, frame.seen
    # Clip fires for a light at the hair's centre (near ≈ 1e-303: xy ~1e300, no int64); outside stays outside.
    tx = np.floor(np.clip(xy[:, 0], -1, resolution)).astype(np.int64)
    ty = np.floor(np.clip(xy[:, 1], -1, resolution)).astype(np.int64)
    inside = seen & (tx >= 0) & (tx < resolution) & (ty >= 0) & (ty < resolution)
    # Per drawn segment (small tables), gathered per fragment where a plan asks.
    strand: Arrays = seg_strand[seg_ids].astype(np.int32)  # int32: the plan keeps it
    factor: Arrays | None = None if inputs.segment_alpha is None else inputs.segment_alpha[seg_ids]
    if on_device:  # the tables go to the fragments' device, the factor in their precision
        strand = jnp.asarray(strand)
        factor = None if factor is None else jnp.asarray(factor, pieces[0].coverage.dtype)
    return LightFragments(
        frame=frame,
        pieces=pieces,
        segment_strand=strand,
        segment_factor=factor,
        tx=tx,
        ty=ty,
        inside=inside,
    )
