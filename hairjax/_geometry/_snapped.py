"""Triangles rasterised as GL rasterises them (docs/model.md §18): coverage on the
window-space vertices rounded to 1/2^RASTER_SUBPIXEL_BITS px with GL's tie rule,
attributes from the unrounded positions. NumPy; the hair patches' rasteriser."""

from __future__ import annotations

import numpy as np

from .._constants import RASTER_SUBPIXEL_BITS
from ._occluder import box_candidates, perspective_correct
from ._projection import View

__all__ = ["snapped_fragments"]

_SUBPIXEL = 1 << RASTER_SUBPIXEL_BITS
# Window coordinates are clipped to ±2²¹ px before rounding, so the int64 edge functions
# (products of differences < 2³⁰ units of 1/256 px) cannot overflow.
_WINDOW_LIMIT = float(1 << 21)


def snapped_fragments(view: View, xy: np.ndarray, depth: np.ndarray, tri: np.ndarray):
    """Every (triangle, pixel centre) pair GL's rasteriser covers, in batches: yields (k:
    index into `tri` `[N]`, pixel `[N]`, λ' `[N, 3]`, front `[N]`). `xy`, `depth`:
    `view.project(vertices)`. docs/model.md §18:

    - coverage on the vertices rounded to the nearest 1/2^RASTER_SUBPIXEL_BITS px (ties to
      even): the pixel centre c is covered when every edge function of the rounded
      triangle, signed to be positive inside, is > 0 at c, or = 0 on a left or bottom edge
      (y down: the inward normal n has n_x > 0, or n_x = 0 and n_y < 0; GL's window y runs
      up, where this is a left or top edge); exact in int64;
    - a triangle whose rounded projection has zero area is not drawn; it faces the viewer
      when that area is negative (counter-clockwise with y up, GL's default);
    - λ' from the unrounded positions (edge functions over the area, then perspective-
      correct λ'_i ∝ λ_i/D_i), so it may be slightly negative at a pixel that only the
      rounding covers."""
    w, h = view.width, view.height
    # The clip fires only for vertices > 2²¹ px off-screen (next to a perspective view's near
    # plane), where GL clips the triangle instead: both then agree up to rounding.
    fixed = np.rint(np.clip(xy, -_WINDOW_LIMIT, _WINDOW_LIMIT) * _SUBPIXEL).astype(np.int64)
    fa, fb, fc = (fixed[tri[:, k]] for k in range(3))
    area_fixed = (fb[:, 0] - fa[:, 0]) * (fc[:, 1] - fa[:, 1]) - (fb[:, 1] - fa[:, 1]) * (fc[:, 0] - fa[:, 0])
    sign = np.sign(area_fixed)
    a, b, c = (xy[tri[:, k]] for k in range(3))
    area = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    # Edge opposite vertex i runs from vertex i + 1 to i + 2; its edge function's gradient,
    # signed to point inside, decides ties (GL's top-left rule, in window y up).
    ends = [(fb, fc), (fc, fa), (fa, fb)]
    tie = [
        ((n_x := sign * (p[:, 1] - q[:, 1])) > 0) | ((n_x == 0) & (sign * (q[:, 0] - p[:, 0]) < 0))
        for p, q in ends
    ]
    # Pixel i's centre is (i + ½)·2^bits in fixed point: columns with it in [min x, max x].
    half = _SUBPIXEL // 2
    corners = fixed[tri]
    x0 = np.clip(-((half - corners[..., 0].min(axis=1)) // _SUBPIXEL), 0, w)
    x1 = np.clip((corners[..., 0].max(axis=1) - half) // _SUBPIXEL, -1, w - 1)
    y0 = np.clip(-((half - corners[..., 1].min(axis=1)) // _SUBPIXEL), 0, h)
    y1 = np.clip((corners[..., 1].max(axis=1) - half) // _SUBPIXEL, -1, h - 1)
    nx = np.maximum(x1 - x0 + 1, 0)
    ny = np.maximum(y1 - y0 + 1, 0)
    # Zero-area rounded projections are not drawn (GL culls them).
    count = np.where(area_fixed != 0, nx * ny, 0)
    for k, px, py in box_candidates(x0, y0, nx, count):
        cx, cy = px * _SUBPIXEL + half, py * _SUBPIXEL + half
        inside = np.ones(k.size, bool)
        for i, (p, q) in enumerate(ends):
            pk, qk = p[k], q[k]
            e = sign[k] * ((pk[:, 0] - cx) * (qk[:, 1] - cy) - (pk[:, 1] - cy) * (qk[:, 0] - cx))
            inside &= (e > 0) | ((e == 0) & tie[i][k])
        k, px, py = k[inside], px[inside], py[inside]
        fx, fy = px + 0.5, py + 0.5
        ak, bk, ck = a[k], b[k], c[k]
        lam_a = ((bk[:, 0] - fx) * (ck[:, 1] - fy) - (bk[:, 1] - fy) * (ck[:, 0] - fx)) / area[k]
        lam_b = ((ck[:, 0] - fx) * (ak[:, 1] - fy) - (ck[:, 1] - fy) * (ak[:, 0] - fx)) / area[k]
        lam = np.stack([lam_a, lam_b, 1.0 - lam_a - lam_b], axis=1)
        if view.perspective:
            lam = perspective_correct(lam, depth[tri[k]])
        yield k, (py * w + px).astype(np.int64), lam, area_fixed[k] < 0
