"""Opacity shadow maps (kim-2003 §4, Routine 2) and their N → ∞ limit (docs/model.md §7).

Ω(D, texel) is the summed fragment alpha, in the light's raster, of everything nearer the
light than depth D. Maps sit on the planes D_i = D_0 + iΔ, i = 0..N, Δ = (D_N − D_0)/N,
between the nearest (D_0) and farthest (D_N) strand point; a point at depth z with
D_i ≤ z ≤ D_{i+1} gets

    Ω = (1 − f) Ω̄(D_i) + f Ω̄(D_{i+1}),   f = (z − D_i)/Δ,

with Ω̄ the 3 × 3 box average around the point's texel (texels outside the map count 0).
`exact` uses Ω̄(z) itself, the limit N → ∞.

Set-up (NumPy, geometry only) rasterises the strands from the light and plans the
gathers; evaluation (JAX) is linear in fragment alpha, so Ω is differentiable in opacity.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, Int

from ._composite import segmented_scan
from ._constants import PIXEL_HALF_EXTENT, SHADOW_FILTER_RADIUS
from ._projection import View, light_view
from ._raster import rasterize, ribbon_widths

__all__ = ["ShadowSetup", "LightFrame", "light_frame", "point_planes", "shadow_setup", "with_receivers",
           "opacity_maps", "point_opacity", "MAX_MAP_CELLS"]

# (N + 1) · R² map cells at most: 1 GiB in float32.
MAX_MAP_CELLS = 1 << 28


@dataclasses.dataclass(frozen=True)
class ShadowSetup:
    """What Ω needs that does not depend on opacity.

    `frag_strand[F]`, `frag_coverage[F]`: light-space fragments. For `opacity-maps`:
    `frag_cell[F]` = slice · R² + texel (slice N: beyond the last plane, dropped) and per
    point the plane index `plane[P]`, its weight `f[P]` and texel `texel[P]` (−1 outside).
    For `exact`: fragments sorted by (texel, depth) with `frag_first[F]`, and per point
    `index[P, 9]`, `weight[P, 9]` into the per-texel prefix sums.
    """

    method: str
    view: View
    frag_strand: np.ndarray
    frag_coverage: np.ndarray
    frag_cell: np.ndarray | None = None
    plane: np.ndarray | None = None
    f: np.ndarray | None = None
    texel: np.ndarray | None = None
    frag_first: np.ndarray | None = None
    index: np.ndarray | None = None
    weight: np.ndarray | None = None


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
        raise ValueError(f"ribbons {float(np.max(width)):g} world units wide are up to "
                         f"{float(np.max(texels, initial=0.0)):.3g} texels wide in the light's "
                         f"{resolution}² view: too wide for its border; use a higher "
                         "shadows.resolution or a smaller hair.width")
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

    def slice_coordinate(self, z: np.ndarray, maps: int) -> np.ndarray:
        """(z − D₀)·N/span: exactly N at z = D_N, so the farthest points' own fragments
        never count as nearer than the last plane."""
        return (z - self.zmin) * maps / self.span


def light_frame(points, segments, width, light, resolution: int,
                width_units: str = "pixels") -> LightFrame:
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
    return dataclasses.replace(frame, xy=np.concatenate([frame.xy, xy]),
                               depth=np.concatenate([frame.depth, depth]),
                               seen=np.concatenate([frame.seen, seen]))


def shadow_setup(points, segments, seg_strand, width, light, method: str, maps: int,
                 resolution: int, *, receivers: np.ndarray | None = None,
                 segment_alpha: np.ndarray | None = None, width_units: str = "pixels") -> ShadowSetup:
    """Rasterise the strands from the light (same ribbons as the camera pass; width in
    texels = the strand's width in pixels, or its world width seen from the light,
    `ribbon_widths`) and plan Ω at every point, then at every
    point of `receivers` (`[Q, 3]`, optional: the per-point arrays get P + Q entries).
    `segment_alpha` (optional, `[E]`): a factor on each segment's opacity (the alpha
    texture, §17)."""
    if method == "opacity-maps" and (maps + 1) * resolution**2 > MAX_MAP_CELLS:
        raise ValueError(f"{maps} maps of {resolution}² exceed {MAX_MAP_CELLS} cells; "
                         "use fewer maps or a lower resolution")
    frame = light_frame(points, segments, width, light, resolution, width_units)
    seg_ids = frame.drawable
    s0, s1 = segments[seg_ids, 0], segments[seg_ids, 1]
    widths = ribbon_widths(width[seg_strand[seg_ids]], width_units, frame.depth[s0], frame.depth[s1],
                           frame.view.focal, frame.view.perspective)
    frags = rasterize(frame.xy[s0], frame.xy[s1], frame.depth[s0], frame.depth[s1],
                      widths, resolution, resolution, frame.view.perspective)
    frame = with_receivers(frame, receivers)
    view, xy, depth, seen, zmin, span = (frame.view, frame.xy, frame.depth, frame.seen,
                                         frame.zmin, frame.span)

    # Clip fires for a light at the hair's centre (near ≈ 1e-303: xy ~1e300, no int64); outside stays outside.
    tx = np.floor(np.clip(xy[:, 0], -1, resolution)).astype(np.int64)
    ty = np.floor(np.clip(xy[:, 1], -1, resolution)).astype(np.int64)
    inside = seen & (tx >= 0) & (tx < resolution) & (ty >= 0) & (ty < resolution)
    coverage = frags.coverage
    if segment_alpha is not None:
        coverage = coverage * segment_alpha[seg_ids[frags.segment]]
    common = dict(view=view, frag_strand=seg_strand[seg_ids[frags.segment]],
                  frag_coverage=coverage)

    if method == "opacity-maps":
        # A fragment in [D_j, D_{j+1}) counts towards planes j + 1 … N (strictly nearer).
        # The clip fires only through rounding (a depth ulps below D₀ → slice 0); D_N gives N.
        j = np.clip(np.floor(frame.slice_coordinate(frags.depth, maps)), 0, maps).astype(np.int64)
        plane, f = point_planes(frame, maps)
        return ShadowSetup(method=method, frag_cell=(j * resolution**2 + frags.pixel).astype(np.int32),
                           plane=plane.astype(np.int32), f=f,
                           texel=np.where(inside, ty * resolution + tx, -1).astype(np.int32),
                           **common)

    # exact: fragments sorted by one float key, texel + depth fraction / 2.
    def key(texel, z):
        # The clip fires for depths outside [D₀, D_N]: unseen points (masked below), rounding.
        return texel + 0.5 * np.clip((z - zmin) / span, 0.0, 1.0)

    frag_key = key(frags.pixel.astype(np.float64), frags.depth)
    order = np.argsort(frag_key)
    frag_key = frag_key[order]
    first = np.ones(frags.size, bool)
    first[1:] = frags.pixel[order][1:] != frags.pixel[order][:-1]
    r = SHADOW_FILTER_RADIUS
    offs = np.arange(-r, r + 1)
    ox, oy = np.meshgrid(offs, offs)  # all (2r + 1)² offsets
    nx = tx[:, None] + ox.ravel()[None, :]
    ny = ty[:, None] + oy.ravel()[None, :]
    # Fails for neighbours outside the map (points beyond ±80°) and unseen points: weight 0.
    valid = (nx >= 0) & (nx < resolution) & (ny >= 0) & (ny < resolution) & seen[:, None]
    texel = np.where(valid, ny * resolution + nx, 0).astype(np.float64)
    start = np.searchsorted(frag_key, texel, side="left")
    stop = np.searchsorted(frag_key, key(texel, depth[:, None]), side="left")
    # [start, stop): the texel's fragments strictly nearer the light than the point; the
    # per-texel inclusive prefix at stop − 1 sums them.
    has_any = valid & (stop > start)
    common["frag_strand"] = common["frag_strand"][order]
    common["frag_coverage"] = common["frag_coverage"][order]
    return ShadowSetup(method=method, frag_first=first,
                       index=np.where(has_any, stop - 1, 0),
                       weight=np.where(has_any, 1.0 / (2 * r + 1) ** 2, 0.0), **common)


def point_planes(frame: LightFrame, maps: int) -> tuple[np.ndarray, np.ndarray]:
    """Each point's plane i (its slice, clamped to 0 … N − 1) and weight f ∈ [0, 1]."""
    u = frame.slice_coordinate(frame.depth, maps)
    # The clips fire at D_N (u = N: plane N − 1, f = 1) and for unseen points (u < 0: 0, 0).
    plane = np.clip(np.floor(u), 0, maps - 1).astype(np.int64)
    return plane, np.clip(u - plane, 0.0, 1.0)


def box_filter(maps: Float[Array, "n r r"]) -> Float[Array, "n r r"]:
    """(2r + 1)² box average over texels, zero outside the map."""
    r = SHADOW_FILTER_RADIUS
    k = 2 * r + 1
    padded = jnp.pad(maps, ((0, 0), (r, r), (r, r)))
    rows = sum(padded[:, i:i + maps.shape[1], :] for i in range(k))
    return sum(rows[:, :, i:i + maps.shape[2]] for i in range(k)) / (k * k)


def opacity_maps(frag_alpha: Float[Array, " f"], frag_cell: Int[Array, " f"], maps: int,
                 resolution: int) -> Float[Array, "n1 r r"]:
    """Box-filtered Ω̄ on the N + 1 planes (plane 0 is empty): kim-2003 Routine 2's
    accumulation, with each slice added to the ones behind it (GL_ONE, GL_ONE)."""
    cells = resolution * resolution
    slices = jax.ops.segment_sum(frag_alpha, frag_cell, num_segments=(maps + 1) * cells)
    slices = slices.reshape(maps + 1, resolution, resolution)[:maps]
    omega = jnp.concatenate([jnp.zeros_like(slices[:1]), jnp.cumsum(slices, axis=0)])
    return box_filter(omega)


def point_opacity(maps: Float[Array, "n1 r r"], plane: Int[Array, " p"], f: Float[Array, " p"],
                  texel: Int[Array, " p"]) -> Float[Array, " p"]:
    """Ω at points: linear interpolation between the two planes around each point."""
    flat = maps.reshape(maps.shape[0], -1)
    safe = jnp.maximum(texel, 0)  # fires for texel −1 (outside): any valid index, dropped below
    omega = (1 - f) * flat[plane, safe] + f * flat[plane + 1, safe]
    # Fires for points outside the light's map (behind a point light): no shadow.
    return jnp.where(texel >= 0, omega, 0.0)


def exact_opacity(frag_alpha: Float[Array, " f"], frag_first, index: Int[Array, "p k"],
                  weight: Float[Array, "p k"]) -> Float[Array, " p"]:
    """Ω̄(z) at each point's own depth from per-texel prefix sums (N → ∞)."""
    if frag_alpha.shape[0] == 0:  # fires when no segment reaches the light's raster: Ω = 0
        return jnp.zeros(index.shape[0], frag_alpha.dtype)
    prefix = segmented_scan(frag_alpha, frag_first, jnp.add)
    return jnp.sum(weight * prefix[index], axis=1)
