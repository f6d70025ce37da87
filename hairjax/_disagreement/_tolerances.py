"""The cross-check's tolerances, and "near" in float32 (docs/model.md §11).

- PIXEL_TOL, TAU_TOL = 1e-4 per pixel / per τ: float32 arithmetic on values ≤ 1 with ~10²
  operations per fragment and up to ~10³ fragments composited per pixel gives errors
  ~10⁻⁵; 1e-4 is the cross-check's bound (tests/gl/test_renderer.py gives the measurements).
- `s_delta`, 4 float32 ulps of the raster's largest coordinate, for "near a segment end".
- SLICE_DELTA = 1e-4 slice units for "near a slice boundary": depth relative error ~1e-7,
  times N/span.
- MAX_BAND = 1e-3: the share of pixels the camera band may hold (the cross-check's bound).
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "PIXEL_TOL",
    "TAU_TOL",
    "SLICE_DELTA",
    "MAX_BAND",
    "OCCLUDER_EDGE_DELTA",
    "OCCLUDER_VERTEX_STEP",
    "s_delta",
]

PIXEL_TOL = 1e-4
TAU_TOL = 1e-4
SLICE_DELTA = 1e-4
MAX_BAND = 1e-3
# A mesh occluder's pixel centres within this many pixels of an edge where its coverage
# jumps may fall on either side: llvmpipe rounds vertices to 1/256 pixel (8 sub-pixel
# bits) before its edge test, moving an edge by up to √2/512 ≈ 0.003 px (measured: an
# edge 0.001 px beyond a pixel centre still covers it in GL, one 0.002 px beyond does
# not); 4/256 is that with a 5× margin (no occluder pixel outside it differs on
# tests/geometry/test_occluder.py's scenes).
OCCLUDER_EDGE_DELTA = 4 / 256
# The same rounding moves each projected vertex by ≤ 1/512 px per axis, and GL's
# interpolated normal with it: inside triangles much smaller than a pixel by enough to
# matter (measured 1.1e-4 at one pixel of Sintel at 64²; JAX with vertices rounded to
# 1/256 differs from JAX by 2.3e-4 there, GL lies between). `interpolation_bound` bounds
# it to first order with that step; tests/geometry/test_occluder.py checks GL stays within it.
OCCLUDER_VERTEX_STEP = 1 / 512


def s_delta(w: int, h: int) -> float:
    """4 float32 ulps of the raster's largest coordinate: GL projects points in float32,
    so screen coordinates carry about one ulp of error and s = (c − p₀)·u a few; 4 ulps is
    the measured envelope (at 2 ulps the default scene leaves unexplained pixels)."""
    return 4 * float(np.spacing(np.float32(max(w, h))))
