"""The raster's per-segment layout (docs/model.md §5): each ribbon's width in pixels at
its two ends, and the columns along its major axis with the candidate rows around its
line in each. Laid out in NumPy float64 once per raster, and read alike by the compiled
loop on the host (`_raster`) and the XLA program on a device (`_device_raster`), so that
both visit the same candidates."""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from .._constants import PIXEL_CENTRE, PIXEL_HALF_EXTENT

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
    """The segments' columns and candidate rows, laid out in NumPy float64 (`rasterize`'s
    arguments)."""
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
    # Pixel centres k + PIXEL_CENTRE strictly inside (min a − reach, max a + reach) along
    # the major axis, clipped to the image (the clip also bounds work for off-screen segments).
    lo = np.clip(np.floor(np.minimum(a0, a1) - reach - PIXEL_CENTRE) + 1, 0, size_a)
    hi = np.clip(np.ceil(np.maximum(a0, a1) + reach - PIXEL_CENTRE) - 1, -1, size_a - 1)
    # Zero-length segments (repeated points) cover nothing: a ribbon of length 0.
    columns = np.where(length > 0, np.maximum(hi - lo + 1, 0), 0).astype(np.int64)
    # Rows per column: pixel centres in an open interval of length 2·reach/|u_major| ≤
    # 2·reach·√2 around the line; an interval of length ℓ holds at most ⌈ℓ⌉ + 1 of them.
    rows = int(np.ceil(2 * float(reach.max(initial=0.0)) * np.sqrt(2))) + 1  # initial: no segments

    # Per segment, what the kernel needs, cast from float64 to the kernel's precision.
    seg_data = np.stack(
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
    ).astype(jnp.result_type(float))
    return RasterPlan(seg_data, lo.astype(np.int64), columns, rows)
