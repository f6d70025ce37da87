"""One coverage formula for both rasters (hairjax/_geometry/_coverage.py, docs/model.md §5):
compiled by numba for the host loop and traced by JAX for the device program, it gives
the same values bit for bit, in the precision it was given."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from hairjax._constants import PIXEL_CENTRE, PIXEL_HALF_EXTENT
from hairjax._geometry._coverage import coverage_formula
from hairjax._geometry._raster_loop import coverage_loop


def _cases(dtype):
    """Distances and widths around every kink of the formula (d ± ½ = ±w/2, the clamps at
    0 and 1), one float either side of each, and random ones."""
    rng = np.random.default_rng(7)
    width = np.concatenate([[0.01, 0.25, 0.5, 1.0, 1.5, 2.0, 3.0, 7.25], rng.uniform(0.0, 6.0, 200)])
    d = np.concatenate(
        [
            np.abs(width / 2 - PIXEL_HALF_EXTENT),
            width / 2 + PIXEL_HALF_EXTENT,
            np.zeros_like(width),
            rng.uniform(0.0, 4.0, width.size),
        ]
    ).astype(dtype)
    width = np.tile(width, 4).astype(dtype)
    d = np.concatenate([d, np.nextafter(d, dtype(-1)), np.nextafter(d, dtype(np.inf))])
    return np.abs(d), np.tile(width, 3)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_the_host_loop_and_the_device_program_cover_alike(dtype):
    d, width = _cases(dtype)
    host_coverage = coverage_loop(np.dtype(dtype).name)
    host = np.array([host_coverage(a, b) for a, b in zip(d, width)], dtype)
    device = np.asarray(jax.jit(coverage_formula(dtype, jnp.minimum, jnp.maximum))(d, width))
    assert device.dtype == dtype  # no constant widened it
    assert 0 < np.count_nonzero(host == 0) < host.size  # both clamps and the ramp are met
    assert 0 < np.count_nonzero(host == 1) < host.size
    np.testing.assert_array_equal(device.view(np.uint8), host.view(np.uint8))


def test_the_pixel_centre_is_half_the_pixels_extent_from_its_corner():
    # The rasters sample at (x + PIXEL_CENTRE, y + PIXEL_CENTRE) and cover a box of half
    # extent PIXEL_HALF_EXTENT around that point: the unit box [x, x + 1) × [y, y + 1).
    assert PIXEL_CENTRE - PIXEL_HALF_EXTENT == 0.0
    assert PIXEL_CENTRE + PIXEL_HALF_EXTENT == 1.0
