"""The raster's per-segment layout (docs/model.md §5): each ribbon's width in pixels at
its two ends, and the columns along its major axis with the candidate rows around its
line in each. Laid out in float64 once per raster, and read alike by the compiled
loop on the host (`_raster`) and the XLA program on a device (`_device_raster`), so that
both visit the same candidates."""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import NamedTuple, no_type_check

import jax.numpy as jnp
import numpy as np

from .._constants import PIXEL_CENTRE, PIXEL_HALF_EXTENT
from ._host import compile_loop

__all__ = ["RibbonRaster", "RasterPlan", "raster_plan", "ribbon_widths"]


class RibbonRaster(NamedTuple):
    """A raster's input, `rasterize`'s arguments by name (and in order): per segment its
    ends `xy0`, `xy1` (`[E, 2]` pixel coordinates), their depths `z0`, `z1` (`[E]`) and
    the ribbon's `width` (`[E]` pixels, or `[E, 2]` at each end: `ribbon_widths`); the
    raster's size; whether depth is interpolated perspective-correctly."""

    xy0: np.ndarray
    xy1: np.ndarray
    z0: np.ndarray
    z1: np.ndarray
    width: np.ndarray
    image_width: int
    image_height: int
    perspective: bool

    @property
    def pixels(self) -> int:
        """The raster's number of pixels, H·W."""
        return self.image_width * self.image_height


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
class RasterPlan:
    """What the raster needs per segment, shared by the compiled loop on the host
    (`rasterize_parts`) and the XLA program on a device (`_device_raster`): `seg_data`
    (`[E, 11]`, JAX's default float precision: x0, y0, dx, dy, L, w₀, z0, z1, x-major,
    reach, w₁), each segment's first pixel column `lo` and its number of `columns`
    (`[E]` int64, along its major axis), and the candidate `rows` per column."""

    seg_data: np.ndarray
    lo: np.ndarray
    columns: np.ndarray
    rows: int


def raster_plan(xy0, xy1, z0, z1, width, image_width: int, image_height: int) -> RasterPlan:
    """The segments' columns and candidate rows, laid out in float64 (`rasterize`'s
    arguments) by one compiled step per segment (`_plan_loop`): NumPy's two dozen passes
    over the 2 M ribbons of 100k strands, camera and light, took 0.3 s."""
    xy0 = np.ascontiguousarray(xy0, np.float64)
    xy1 = np.ascontiguousarray(xy1, np.float64)
    n = xy0.shape[0]
    width = np.asarray(width, np.float64)
    widths = np.ascontiguousarray(np.broadcast_to(width if width.ndim == 2 else width[..., None], (n, 2)))
    z0 = np.ascontiguousarray(np.broadcast_to(np.asarray(z0, np.float64), (n,)))
    z1 = np.ascontiguousarray(np.broadcast_to(np.asarray(z1, np.float64), (n,)))
    # Per segment, what the kernel needs, cast from float64 to the kernel's precision.
    seg_data = np.empty((n, 11), jnp.result_type(float))
    lo, columns = np.empty(n, np.int64), np.empty(n, np.int64)
    widest = _plan_loop()(xy0, xy1, z0, z1, widths, image_width, image_height, seg_data, lo, columns)
    # Rows per column: pixel centres in an open interval of length 2·reach/|u_major| ≤
    # 2·reach·√2 around the line; an interval of length ℓ holds at most ⌈ℓ⌉ + 1 of them.
    rows = int(np.ceil(2 * widest * np.sqrt(2))) + 1
    return RasterPlan(seg_data, lo, columns, rows)


@functools.cache
def _plan_loop():
    """`raster_plan`'s step per segment compiled by numba (on first use; cached on disk),
    in float64, the seg_data row cast once to its array's type; it returns the widest
    reach (0 without segments)."""

    @compile_loop(error_model="numpy")
    @no_type_check
    def plan(xy0, xy1, z0, z1, widths, image_width, image_height, seg_data, lo, columns):
        widest = 0.0
        for i in range(xy0.shape[0]):
            x0, y0, x1, y1 = xy0[i, 0], xy0[i, 1], xy1[i, 0], xy1[i, 1]
            dx, dy = x1 - x0, y1 - y0
            length = math.hypot(dx, dy)
            x_major = abs(dx) >= abs(dy)
            # The wider end bounds the footprint; its half-extent across the ribbon:
            reach = 0.5 * max(widths[i, 0], widths[i, 1]) + PIXEL_HALF_EXTENT
            widest = max(widest, reach)
            a0, a1 = (x0, x1) if x_major else (y0, y1)
            size_a = image_width if x_major else image_height
            # Pixel centres k + PIXEL_CENTRE strictly inside (min a − reach, max a + reach)
            # along the major axis, clipped to the image (the clip also bounds work for
            # off-screen segments).
            first = min(max(np.floor(min(a0, a1) - reach - PIXEL_CENTRE) + 1, 0.0), size_a)
            last = min(max(np.ceil(max(a0, a1) + reach - PIXEL_CENTRE) - 1, -1.0), size_a - 1)
            lo[i] = np.int64(first)
            # Zero-length segments (repeated points) cover nothing: a ribbon of length 0.
            columns[i] = np.int64(max(last - first + 1, 0.0)) if length > 0 else 0
            row = seg_data[i]
            row[0], row[1], row[2], row[3], row[4] = x0, y0, dx, dy, length
            row[5], row[6], row[7], row[8] = widths[i, 0], z0[i], z1[i], 1.0 if x_major else 0.0
            row[9], row[10] = reach, widths[i, 1]
        return widest

    return plan
