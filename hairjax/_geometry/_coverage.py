"""A pixel's coverage by a ribbon (kim-2003 §2; docs/model.md §5), one formula for both of
the set-up's rasters: the loop compiled by numba on the host (`_raster`) and the XLA
program on a device (`_device_raster`). GLSL's `ribbon_coverage` (gl/shaders/model.glsl)
writes the same formula with the same constant, `PIXEL_HALF_EXTENT`, injected from
`hairjax/_constants.py`.

The formula is plain arithmetic over its arguments, its constants and a `minimum` and
`maximum` handed in: Python's `min` and `max` where numba compiles it for scalars, and
`jnp.minimum`, `jnp.maximum` where JAX traces it over arrays. Each caller thus runs the
operations it ran with its own copy, in the same order, so its fragments stay bit for bit
what they were (tests/geometry/test_device_raster.py).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, no_type_check

from .._constants import PIXEL_HALF_EXTENT

__all__ = ["coverage_formula"]


def coverage_formula(float_type: Any, minimum: Callable, maximum: Callable) -> Callable:
    """`coverage(d, width)`: the overlap of a unit pixel box at distance `d` from a
    ribbon's axis with the ribbon's cross-section of `width` (docs/model.md §5),

        clamp(min(d + ½, w/2) − max(d − ½, −w/2), 0, 1),

    for one candidate, or elementwise over arrays where `minimum` and `maximum` are.

    **Arguments:** `float_type`: the scalar type of the caller's floats (`np.float32` or
    `np.float64`); every constant has that type, so no operation widens to float64 under
    numba. `minimum`, `maximum`: elementwise min and max of two values (`min`, `max` for
    numba's scalars; `jnp.minimum`, `jnp.maximum` for JAX's arrays).

    **Returns:** the function, not compiled: numba compiles it (`_raster`), JAX traces it
    (`_device_raster`).
    """
    zero, one = float_type(0.0), float_type(1.0)
    half, half_extent = float_type(0.5), float_type(PIXEL_HALF_EXTENT)

    # no_type_check: the tests' jaxtyping hook would otherwise wrap it before numba.
    @no_type_check
    def coverage(d, width):
        half_width = half * width
        overlap = minimum(d + half_extent, half_width) - maximum(d - half_extent, -half_width)
        return minimum(maximum(overlap, zero), one)

    return coverage
