"""The compositing weights at concrete opacities on the host (hairjax/_geometry/_weights.py,
docs/model.md §6): JAX's product scan's within its rounding, the hidden ones left out,
and each pixel's weights independent of where its run lies."""

import jax.numpy as jnp
import numpy as np
import pytest

from hairjax._geometry._capacity import fragment_bucket
from hairjax._geometry._weights import host_weights
from hairjax._geometry_stage._fragments import PaddedFragments
from hairjax._geometry_stage._stage import composite_weights

HW = 30
DTYPE = jnp.result_type(float)  # the tests run in float64 (conftest)


def _fragments(seed=0, n=3000, drop_pixel=None):
    """Fragments of 40 strands over HW pixels, sorted by pixel, padded to their bucket."""
    rng = np.random.default_rng(seed)
    pixel = np.sort(rng.integers(0, HW, n)).astype(np.int32)
    i0 = rng.integers(0, 200, n).astype(np.int32)
    coverage = rng.uniform(0.05, 1.0, n)
    t = rng.uniform(0, 1, n)
    if drop_pixel is not None:
        keep = pixel != drop_pixel
        pixel, i0, coverage, t = pixel[keep], i0[keep], coverage[keep], t[keep]
    size = fragment_bucket(pixel.size)
    pad = lambda x, v: np.concatenate([x, np.full(size - x.size, v, x.dtype)])  # noqa: E731
    return PaddedFragments(
        pad(pixel, HW), pad(i0, 0), pad(coverage.astype(DTYPE), 0), pad(t.astype(DTYPE), 0)
    )


def _inputs(seed=1):
    rng = np.random.default_rng(seed)
    alpha = rng.uniform(0.2, 0.9, 40).astype(DTYPE)
    strand_of_point = (np.arange(201) // 5).astype(np.int32)
    opaque = rng.uniform(size=HW) < 0.2
    return alpha, strand_of_point, opaque


def test_the_host_weights_are_the_scans_within_its_rounding():
    alpha, strand_of_point, opaque = _inputs()
    frags = _fragments()
    ours = host_weights(alpha, strand_of_point, frags, opaque, None, 0.0, DTYPE)
    weights, transmittance, alpha_channel, _ = composite_weights(
        jnp.asarray(alpha),
        jnp.asarray(strand_of_point),
        jnp.asarray(frags.i0),
        jnp.asarray(frags.coverage),
        jnp.asarray(frags.pixel),
        jnp.asarray(opaque, DTYPE),
    )
    # Each T is a product of at most `longest` factors, each rounding by half an epsilon,
    # grouped otherwise by the scan.
    longest = np.bincount(frags.pixel[frags.pixel < HW]).max()
    rtol = longest * np.finfo(DTYPE).eps
    np.testing.assert_allclose(ours.weight, np.asarray(weights), rtol=rtol, atol=0)
    np.testing.assert_allclose(ours.transmittance, np.asarray(transmittance), rtol=rtol, atol=0)
    np.testing.assert_allclose(ours.alpha_channel, np.asarray(alpha_channel), rtol=rtol, atol=rtol)
    assert ours.pixel is frags.pixel and ours.i0 is frags.i0  # nothing cut: the set-up's own buffers


@pytest.mark.parametrize("cutoff", [1e-3, 1e-6])
def test_the_hidden_fragments_are_left_out_and_the_rest_keep_their_weights(cutoff):
    alpha, strand_of_point, opaque = _inputs()
    frags = _fragments()
    every = host_weights(alpha, strand_of_point, frags, opaque, None, 0.0, DTYPE)
    cut = host_weights(alpha, strand_of_point, frags, opaque, None, cutoff, DTYPE)
    real = frags.pixel < HW
    frag_alpha = alpha[strand_of_point[frags.i0]] * frags.coverage
    seen = real & (every.weight >= cutoff * frag_alpha)
    assert 10 < seen.sum() < real.sum() - 10
    n = int(seen.sum())
    assert (
        cut.pixel.size == fragment_bucket(n) and np.all(cut.pixel[n:] == HW) and np.all(cut.weight[n:] == 0)
    )
    for name, field in (("pixel", frags.pixel), ("i0", frags.i0), ("t", frags.t), ("weight", every.weight)):
        np.testing.assert_array_equal(getattr(cut, name)[:n], field[seen], err_msg=name)
    np.testing.assert_array_equal(cut.transmittance, every.transmittance)  # every fragment dims its pixel


def test_a_pixels_weights_do_not_depend_on_where_its_run_lies():
    """The fragments of one pixel removed: every other pixel's weights are the same, bit
    for bit, though their runs moved in the array (the scan's would round otherwise)."""
    alpha, strand_of_point, opaque = _inputs()
    full, without = _fragments(), _fragments(drop_pixel=3)
    a = host_weights(alpha, strand_of_point, full, opaque, None, 0.0, DTYPE)
    b = host_weights(alpha, strand_of_point, without, opaque, None, 0.0, DTYPE)
    other = (full.pixel < HW) & (full.pixel != 3)
    np.testing.assert_array_equal(b.weight[: other.sum()], a.weight[other])


def test_the_hidden_transmittance_multiplies_each_pixels():
    alpha, strand_of_point, opaque = _inputs()
    hidden = np.random.default_rng(2).uniform(0.5, 1.0, HW)
    plain = host_weights(alpha, strand_of_point, _fragments(), opaque, None, 0.0, DTYPE)
    dimmed = host_weights(alpha, strand_of_point, _fragments(), opaque, hidden, 0.0, DTYPE)
    np.testing.assert_array_equal(dimmed.transmittance, plain.transmittance * hidden.astype(DTYPE))
    np.testing.assert_array_equal(dimmed.alpha_channel, 1 - dimmed.transmittance * (1 - opaque))
