"""Ribbon rasterisation with analytic coverage (kim-2003 §2; docs/model.md §5).

A segment (x0, y0) → (x1, y1) in pixel coordinates is a screen-aligned ribbon of width w.
A pixel centre c, at signed position s = (c − p0)·u along the segment and distance
d = |(c − p0) × u| from its line, is covered by

    coverage = clamp(min(d + ½, w/2) − max(d − ½, −w/2), 0, 1)   if 0 ≤ s < L, else 0,

the overlap of a unit pixel box aligned with the ribbon and the ribbon's cross-section.
The width may differ at the two ends (ribbons of world-space width, `ribbon_widths`): then
w = (1 − t)·w₀ + t·w₁ at the pixel centre's t = s/L.
Along the segment, the half-open interval [0, L) gives every pixel to exactly one of two
collinear neighbours: a straight strand drawn as 1 or 8 segments covers the same pixels
with the same coverage (no double-covered joints, no gaps).

Geometry only, no gradients flow through here: the segments' columns are counted in NumPy
float64; the per-pixel maths runs in one jitted XLA kernel in JAX's default float
precision, which gathers each column's segment data itself (a column carries only its
segment's index and its pixel column).
"""

from __future__ import annotations

import dataclasses
import functools

import jax
import jax.numpy as jnp
import numpy as np

from .._constants import PIXEL_HALF_EXTENT
from ._host import release_heap

__all__ = ["Fragments", "rasterize", "ribbon_coverage", "ribbon_widths"]

_CHUNK = 1 << 20  # columns per kernel call: bounds peak memory to a few hundred MB


def ribbon_coverage(d, width):
    """Coverage of a unit box at distance `d` from the ribbon axis by a ribbon of `width`
    (docs/model.md §5). The rasteriser's kernel calls this, so the tests check what renders."""
    half = 0.5 * width
    return jnp.clip(
        jnp.minimum(d + PIXEL_HALF_EXTENT, half) - jnp.maximum(d - PIXEL_HALF_EXTENT, -half), 0.0, 1.0
    )


def ribbon_widths(
    width: np.ndarray, units: str, depth0: np.ndarray, depth1: np.ndarray, focal: float, perspective: bool
) -> np.ndarray:
    """Each segment's ribbon width in the view's pixels at its two ends (`[E, 2]`,
    docs/model.md §5).

    **Arguments:** `width` per segment (`[E]`) in `units`; the ends' depths (`[E]`); the
    view's `focal` (pixels per unit of lateral offset / depth, or per world unit for an
    orthographic view) and whether it is a perspective view. `"pixels"`: `width` at both
    ends; `"world"`: w·f/D at depth D in perspective, w·f orthographic.
    """
    width = np.asarray(width, np.float64)
    if units == "pixels":
        return np.stack([width, width], axis=1)
    if units != "world":
        raise ValueError(f"width units must be 'pixels' or 'world', got {units!r}")
    if not perspective:
        return np.stack([width * focal, width * focal], axis=1)
    # Drawn segments lie beyond the near plane (D > 0); the caller culls the others.
    return np.stack(
        [width * focal / np.asarray(depth0, np.float64), width * focal / np.asarray(depth1, np.float64)],
        axis=1,
    )


@dataclasses.dataclass(frozen=True)
class Fragments:
    """Pixels covered by segments, grouped by segment in input order.

    `pixel` (int32): row-major pixel index y·W + x; `segment` (int32): index into the input
    arrays; floats are in JAX's default precision (float32, or float64 with x64 on);
    `coverage` ∈ (0, 1]; `t` ∈ [0, 1): screen-space position along the segment;
    `depth`: interpolated depth (perspective-correct for perspective views), or None when
    the raster was asked for none.
    """

    pixel: np.ndarray
    segment: np.ndarray
    coverage: np.ndarray
    t: np.ndarray
    depth: np.ndarray | None

    def take(self, index) -> Fragments:
        depth = None if self.depth is None else self.depth[index]
        return Fragments(self.pixel[index], self.segment[index], self.coverage[index], self.t[index], depth)

    @property
    def depths(self) -> np.ndarray:
        """`depth`, of a raster that interpolated it (ValueError otherwise)."""
        if self.depth is None:
            raise ValueError("this raster interpolated no depth (rasterize(..., depth=False))")
        return self.depth

    @property
    def size(self) -> int:
        return self.pixel.shape[0]


def rasterize(
    xy0: np.ndarray,
    xy1: np.ndarray,
    z0: np.ndarray,
    z1: np.ndarray,
    width: np.ndarray,
    image_width: int,
    image_height: int,
    perspective: bool,
    *,
    depth: bool = True,
) -> Fragments:
    """All (segment, pixel) pairs with positive coverage, segment after segment.

    **Arguments:** per segment `xy0`, `xy1` (`[E, 2]` pixel coordinates), depths `z0`, `z1`
    (`[E]`), ribbon `width` (`[E]` pixels, or `[E, 2]`: at each end, `ribbon_widths`); the
    raster size; whether depth is
    interpolated perspective-correctly (1/z linear in screen space) or linearly; `depth`:
    whether to interpolate it at all (the camera's fragments need it only for an
    occluder's depth test: without, `Fragments.depth` is None and the kernel skips it).

    Columns along each segment's major axis are laid out here in NumPy; the per-pixel
    maths runs in one fused XLA kernel over `[columns, rows]` candidates, in JAX's
    default float precision (float64 when x64 is enabled).
    """
    xy0 = np.asarray(xy0, np.float64)
    xy1 = np.asarray(xy1, np.float64)
    n = xy0.shape[0]
    width = np.asarray(width, np.float64)
    widths = np.broadcast_to(width if width.ndim == 2 else width[..., None], (n, 2))
    width = widths.max(axis=1)  # the wider end bounds the footprint
    z0 = np.broadcast_to(np.asarray(z0, np.float64), (n,))
    z1 = np.broadcast_to(np.asarray(z1, np.float64), (n,))
    delta = xy1 - xy0
    length = np.hypot(delta[:, 0], delta[:, 1])
    x_major = np.abs(delta[:, 0]) >= np.abs(delta[:, 1])
    reach = 0.5 * width + PIXEL_HALF_EXTENT  # footprint half-extent across the ribbon
    a0 = np.where(x_major, xy0[:, 0], xy0[:, 1])
    a1 = np.where(x_major, xy1[:, 0], xy1[:, 1])
    size_a = np.where(x_major, image_width, image_height)
    # Pixel centres k + ½ strictly inside (min a − reach, max a + reach) along the major
    # axis, clipped to the image (the clip also bounds work for off-screen segments).
    lo = np.clip(np.floor(np.minimum(a0, a1) - reach - 0.5) + 1, 0, size_a)
    hi = np.clip(np.ceil(np.maximum(a0, a1) + reach - 0.5) - 1, -1, size_a - 1)
    # Zero-length segments (repeated points) cover nothing: a ribbon of length 0.
    columns = np.where(length > 0, np.maximum(hi - lo + 1, 0), 0).astype(np.int64)
    # Rows per column: pixel centres in an open interval of length 2·reach/|u_major| ≤
    # 2·reach·√2 around the line; an interval of length ℓ holds at most ⌈ℓ⌉ + 1 of them.
    rows = int(np.ceil(2 * float(reach.max(initial=0.0)) * np.sqrt(2))) + 1  # initial: no segments

    # Per segment, what the kernel needs, in the kernel's precision (it computed in that
    # precision before as well): each column then carries only its segment's index and its
    # own pixel column k, and the kernel gathers the segment's row itself.
    # Rows padded with zeros to a bucket of at least n + 1 (the kernel compiles per bucket,
    # and padding columns read row n: length 0).
    seg_data = np.zeros((_bucket(n + 1), 11), jnp.result_type(float))
    seg_data[:n] = np.stack(
        [
            xy0[:, 0],
            xy0[:, 1],
            delta[:, 0],
            delta[:, 1],
            length,
            widths[:, 0],
            z0,
            z1,
            x_major.astype(np.float64),
            reach,
            widths[:, 1],
        ],
        axis=1,
    )
    seg_data = jax.device_put(seg_data)  # once, not with every chunk's call
    # Columns are independent once they know their segment, so they are cut into chunks of
    # exactly _CHUNK (only the last is padded): the kernel compiles for one size.
    seg_of_col = np.repeat(np.arange(n, dtype=np.int32), columns)
    first_col = np.cumsum(columns) - columns
    total = seg_of_col.size
    # The covered candidates are written straight into one array per field, sized for
    # every candidate: pages never written are never resident, so the fields cost what they
    # hold. (Per-chunk parts concatenated at the end had held each fragment twice and left
    # 1.6 GiB of C heap behind at 100k strands / 1024², BENCHMARKS.md "Memory".)
    dtype = jnp.result_type(float)
    fields = [
        np.empty(total * rows, t) for t in (np.int32, np.int32, dtype, dtype, dtype)[: 5 if depth else 4]
    ]
    filled = 0
    for c_lo in range(0, total, _CHUNK):
        seg = seg_of_col[c_lo : c_lo + _CHUNK]
        size = _CHUNK if total > _CHUNK else _bucket(seg.size)
        # k = lo + the column's place in its segment; exact integers in float32 (< 2^24).
        k = np.zeros(size, np.int32)
        k[: seg.size] = lo[seg] + (np.arange(c_lo, c_lo + seg.size) - first_col[seg])
        padded = np.full(size, n, np.int32)  # padding columns read the zero row n
        padded[: seg.size] = seg
        out = _candidates(seg_data, padded, k, rows, image_width, image_height, perspective, depth)
        pixel, cov, *rest = (np.asarray(o)[: seg.size * rows] for o in out)
        keep = np.flatnonzero(cov > 0)
        end = filled + keep.size
        for field, values in zip(fields, (pixel, None, cov, *rest)):
            if values is not None:
                np.take(values, keep, out=field[filled:end])
        fields[1][filled:end] = seg[keep // rows]
        filled = end
    release_heap(total * rows * 20)  # the chunks' temporaries: 4 outputs, keep (int64)
    return Fragments(*(field[:filled] for field in fields), *([] if depth else [None]))


def _bucket(n: int) -> int:
    """Round a size up to a power of two (≥ 4096) so the kernel compiles rarely."""
    return max(4096, 1 << int(np.ceil(np.log2(max(n, 1)))))


@functools.partial(jax.jit, static_argnums=(3, 4, 5, 6, 7))
def _candidates(seg_data, seg, k, rows, image_width, image_height, perspective, with_depth):
    """Candidate pixels `[columns · rows]`: (pixel, coverage, t, depth), depth only
    `with_depth`.

    Coverage 0 marks a candidate that is not drawn (outside the ribbon, the image, or
    padding). A column is the pixel column `k` (row, for y-major segments) of segment
    `seg`, whose row of `seg_data` is (x0, y0, dx, dy, L, w₀, z0, z1, x-major, reach, w₁);
    its candidates are the `rows` pixels around the segment's line there. Padding columns
    read a zero row (length 0).
    """
    dtype = jnp.result_type(float)
    c = seg_data[seg]
    x0, y0, dx, dy, length, w0, za, zb, xm, reach, w1 = (c[:, i, None] for i in range(11))
    k = k.astype(dtype)[:, None]
    xm = xm > 0
    da = jnp.where(xm, dx, dy)
    db = jnp.where(xm, dy, dx)
    # Fires only on padding columns (length 0); a drawn segment has |da| ≥ L/√2 > 0.
    da_safe = jnp.where(da != 0, da, 1.0)
    b_line = jnp.where(xm, y0, x0) + (k + 0.5 - jnp.where(xm, x0, y0)) * (db / da_safe)
    m = jnp.floor(b_line - reach * length / jnp.abs(da_safe) - 0.5) + 1 + jnp.arange(rows)[None, :]
    px = jnp.where(xm, k, m)
    py = jnp.where(xm, m, k)
    # Fires only on padding (length 0): real segments have length > 0.
    inv_len = 1.0 / jnp.where(length > 0, length, 1.0)
    rx = px + 0.5 - x0
    ry = py + 0.5 - y0
    s = (rx * dx + ry * dy) * inv_len
    dist = jnp.abs(rx * dy - ry * dx) * inv_len
    t = s * inv_len
    # w₀ + t(w₁ − w₀) is exactly w₀ for ribbons of constant width (pixel widths).
    cov = ribbon_coverage(dist, w0 + t * (w1 - w0))
    inside = (px >= 0) & (px < image_width) & (py >= 0) & (py < image_height)
    # Padding columns have length 0 and fail s < L.
    valid = inside & (s >= 0) & (s < length)
    cov = jnp.where(valid, cov, 0.0)
    pixel = py.astype(jnp.int32) * image_width + px.astype(jnp.int32)
    if not with_depth:
        return tuple(x.ravel() for x in (pixel, cov, t))
    if perspective:
        # Fires only on padding (depth 0); drawn segments lie beyond the near plane.
        inv = (1 - t) / jnp.where(za != 0, za, 1.0) + t / jnp.where(zb != 0, zb, 1.0)
        depth = 1.0 / jnp.where(inv != 0, inv, 1.0)
        # Fires for segments at constant depth: keep z exactly (no self-shadowing by a
        # rounding error in 1/(1/z)).
        depth = jnp.where(za == zb, za, depth)
    else:
        # z₀ + t(z₁ − z₀) is exactly z₀ for segments at constant depth.
        depth = za + t * (zb - za)
    return tuple(x.ravel() for x in (pixel, cov, t, depth))
