"""The host raster's compiled loops (docs/model.md §5): for each segment of a raster plan
(`_raster_plan`), its columns and the candidate rows around its line in each, every
candidate's coverage (`coverage_formula`, the device program's formula too), position t
and depth, the covered ones written out, but for those behind the occluder or hidden
behind nearer fragments (`_seen`). Compiled by numba for JAX's default float
precision (float32, or float64 with x64 on); `_raster` runs them in pieces on every core.

The loop contracts a·b + c into fused multiply-adds where LLVM finds them, as XLA's CPU
kernel does, so its fragments equal the device program's (`_device_raster`) bit for bit
there (tests/geometry/test_device_raster.py).
"""

from __future__ import annotations

import functools
from typing import no_type_check

import numpy as np

from .._constants import PIXEL_CENTRE
from ._coverage import coverage_formula
from ._host import compile_loop

__all__ = ["coverage_loop", "raster_loop", "seen_through_loop"]

# no_type_check on the loops: the tests' jaxtyping hook would otherwise wrap them before
# numba compiles them.
# error_model numpy: a division by 0 gives inf, as in XLA, without a check per division.
# contract: fused multiply-adds where LLVM finds them, as XLA's CPU kernels have.
# inline="always" on the helpers the loop calls per candidate; the loop unpacks `seen`
# once: a helper taking the tuple per candidate made the camera raster at 100k strands /
# 1024² 2.4× as slow.
_LOOP_OPTIONS = dict(error_model="numpy", fastmath={"contract"})


def _float_type(dtype_name: str):
    return np.float32 if dtype_name == "float32" else np.float64


@functools.cache
def coverage_loop(dtype_name: str):
    """`coverage_formula` compiled by numba for scalars of `dtype_name` (on first use;
    cached on disk, `compile_loop`), with Python's min and max."""
    return compile_loop(**_LOOP_OPTIONS)(coverage_formula(_float_type(dtype_name), min, max))


@functools.cache
def _depth_loop(dtype_name: str):
    """`depth_at(za, zb, t, perspective)`: the depth at t along a segment from depth za to
    zb (docs/model.md §5), compiled by numba for scalars of `dtype_name`."""
    one = _float_type(dtype_name)(1.0)

    @compile_loop(**_LOOP_OPTIONS)
    @no_type_check
    def depth_at(za, zb, t, perspective):
        if za == zb:
            # Fires for segments at constant depth: keep z exactly (no self-shadowing by a
            # rounding error in 1/(1/z)).
            return za
        if perspective:
            # Drawn segments lie beyond the near plane: za, zb > 0.
            return one / ((one - t) / za + t / zb)
        return za + t * (zb - za)

    return depth_at


@functools.cache
def seen_through_loop():
    """`seen_through(alpha, pixel, transmittance, hidden, cutoff)` compiled by numba:
    whether a fragment of opacity `alpha` at `pixel` is seen through at least `cutoff` of
    its pixel's running `transmittance`, which it then dims; a hidden one dims `hidden`
    instead (`[H·W]` float64 each, in place; `_seen`). T only falls along a pixel's run
    (docs/model.md §6): once below the cutoff, every later fragment is hidden."""

    @compile_loop(error_model="numpy", inline="always")
    @no_type_check
    def seen_through(alpha, pixel, transmittance, hidden, cutoff):
        through = 1.0 - alpha
        if transmittance[pixel] < cutoff:
            hidden[pixel] *= through
            return False
        transmittance[pixel] *= through
        return True

    return seen_through


@functools.cache
def _rows_loop(dtype_name: str):
    """`in_image(row0, rows, across)` compiled by numba for floats of `dtype_name`: the
    range of a column's candidate rows (from row0, `rows` of them) whose centres may lie
    in the image, `across` rows wide, with one to spare each side. The others would be
    skipped one by one, and a ribbon far wider than the image has millions of them.
    Where row0 is not exact in the float type, all rows."""
    # Integers below it, and their sums with a row index, are exact.
    exact_limit = _float_type(dtype_name)(1 << 23)

    @compile_loop(**_LOOP_OPTIONS, inline="always")
    @no_type_check
    def in_image(row0, rows, across):
        if abs(row0) < exact_limit:
            return max(0, int(-row0) - 1), min(rows, int(across - row0) + 2)
        return 0, rows

    return in_image


@functools.cache
def raster_loop(dtype_name: str):
    """The raster loop compiled by numba for floats of `dtype_name` (on first use; cached
    on disk, `compile_loop`); every constant has that type, so no operation widens to
    float64. It returns the number of covered candidates of segments first … last − 1 and,
    unless count_only, writes to `out` (pixel, segment, coverage, t, depth) those `seen` =
    (hit, opacity, transmittance, hidden, cutoff) keeps: not behind the occluder's `hit`
    depth at their pixel (`[H·W]` float64; empty: no occluder) nor, with `opacity`
    (`[labels]` float64; empty: no cut), hidden (`seen_through`)."""
    F = _float_type(dtype_name)
    one, centre = F(1.0), F(PIXEL_CENTRE)
    in_image = _rows_loop(dtype_name)
    coverage, depth_at, seen_through = coverage_loop(dtype_name), _depth_loop(dtype_name), seen_through_loop()

    @compile_loop(**_LOOP_OPTIONS)
    @no_type_check
    def raster(
        seg_data,
        labels,
        lo,
        columns,
        rows,
        image_width,
        image_height,
        perspective,
        with_depth,
        seen,
        first,
        last,
        count_only,
        *out,
    ):
        out_pixel, out_segment, out_coverage, out_t, out_depth = out
        hit, opacity, transmittance, hidden, cutoff = seen  # `_seen`
        test_hit, cut = hit.size > 0, opacity.size > 0
        filled = 0
        for i in range(first, last):
            x0, y0, dx, dy, length, w0, za, zb, xm, reach, w1 = seg_data[i]
            # A segment with columns has length > 0, so |da| ≥ L/√2 > 0: no guard divides.
            x_major = xm > 0
            da = dx if x_major else dy
            inv_len = one / length
            slope = (dy if x_major else dx) / da
            offset = reach * length / abs(da)
            a_origin = x0 if x_major else y0
            b_origin = y0 if x_major else x0
            for j in range(columns[i]):
                # Column k = lo + j (exact in float32: < 2^24), its candidates the rows around the line.
                k = F(lo[i] + j)
                b_line = b_origin + (k + centre - a_origin) * slope
                row0 = np.floor(b_line - offset - centre) + one
                for r in range(*in_image(row0, rows, image_height if x_major else image_width)):
                    m = row0 + F(r)
                    px, py = (k, m) if x_major else (m, k)
                    rx = px + centre - x0
                    ry = py + centre - y0
                    s = (rx * dx + ry * dy) * inv_len
                    inside = (px >= 0) & (px < image_width) & (py >= 0) & (py < image_height)
                    if not (inside and s >= 0 and s < length):
                        continue
                    t = s * inv_len
                    # w₀ + t(w₁ − w₀) is exactly w₀ for ribbons of constant width (pixel widths).
                    cov = coverage(abs(rx * dy - ry * dx) * inv_len, w0 + t * (w1 - w0))
                    if not cov > 0:
                        continue
                    pixel = np.int32(py) * image_width + np.int32(px)
                    if not count_only:
                        if test_hit and not depth_at(za, zb, t, perspective) < hit[pixel]:
                            continue  # behind the occluder (kim-2003 §3: depth test on)
                        if cut and not seen_through(
                            opacity[labels[i]] * cov, pixel, transmittance, hidden, cutoff
                        ):
                            continue  # hidden (`_seen`)
                        out_pixel[filled], out_segment[filled] = pixel, labels[i]
                        out_coverage[filled], out_t[filled] = cov, t
                        if with_depth:
                            out_depth[filled] = depth_at(za, zb, t, perspective)
                    filled += 1
        return filled

    return raster
