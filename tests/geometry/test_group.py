"""Fragments grouped by pixel, raster order kept (hairjax/_geometry/_group.py, docs/model.md §6)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hairjax._geometry import _group
from hairjax._geometry._group import group_by_pixel
from hairjax._geometry._host import ALIGNMENT


def test_grouping_by_hand():
    pixel = np.array([2, 0, 2, 1, 0], np.int32)
    segment = np.array([10, 11, 12, 13, 14], np.int32)
    coverage = np.array([0.5, 0.25, 1.0, 0.125, 0.75], np.float32)
    # Pixel 0 holds fragments 1 and 4, pixel 1 fragment 3, pixel 2 fragments 0 and 2,
    # each pixel's in the given order; pixel 3 none.
    sorted_pixel, (seg, cov) = group_by_pixel(pixel, 4, segment, coverage)
    np.testing.assert_array_equal(sorted_pixel, [0, 0, 1, 2, 2])
    np.testing.assert_array_equal(seg, [11, 14, 13, 10, 12])
    np.testing.assert_array_equal(cov, np.array([0.25, 0.75, 0.125, 0.5, 1.0], np.float32))
    assert sorted_pixel.dtype == np.int32 and seg.dtype == np.int32 and cov.dtype == np.float32
    for out in (sorted_pixel, seg, cov):  # shared with the CPU device, not copied (`_host`)
        assert out.ctypes.data % ALIGNMENT == 0


@given(
    st.integers(1, 40),
    st.lists(st.integers(0, 10**6), max_size=300),
    st.integers(1, 3),
    st.sampled_from([np.int32, np.float32, np.float64]),
)
@settings(max_examples=60, deadline=None)
def test_grouping_is_a_stable_sort(n_pixels, raw, n_fields, dtype):
    pixel = (np.asarray(raw, np.int64) % n_pixels).astype(np.int32)
    fields = [(np.arange(pixel.size) * (k + 3)).astype(dtype) for k in range(n_fields)]
    order = np.argsort(pixel, kind="stable")
    sorted_pixel, grouped = group_by_pixel(pixel, n_pixels, *fields)
    np.testing.assert_array_equal(sorted_pixel, pixel[order])
    assert len(grouped) == n_fields
    for field, got in zip(fields, grouped):
        assert got.dtype == field.dtype
        np.testing.assert_array_equal(got, field[order])


@pytest.mark.parametrize("threads", [2, 3, 7])
def test_parts_on_several_threads_give_the_same_grouping(monkeypatch, threads):
    """Above PARALLEL_MIN fragments each core scatters its own part into its own slots of
    every pixel's run; lowered here, so that small inputs take that path."""
    monkeypatch.setattr(_group, "PARALLEL_MIN", 1)
    monkeypatch.setattr(_group, "host_threads", lambda: threads)
    rng = np.random.default_rng(threads)
    pixel = rng.integers(0, 13, 500).astype(np.int32)  # runs that every part adds to
    segment = np.arange(500, dtype=np.int32)
    order = np.argsort(pixel, kind="stable")
    sorted_pixel, (seg,) = group_by_pixel(pixel, 13, segment)
    np.testing.assert_array_equal(sorted_pixel, pixel[order])
    np.testing.assert_array_equal(seg, segment[order])


def test_bad_input_is_refused_before_the_unchecked_kernel():
    field = np.zeros(3, np.float32)
    with pytest.raises(ValueError, match="pixel index 4 is outside the 4 pixels"):
        group_by_pixel(np.array([0, 4, 1], np.int32), 4, field)
    with pytest.raises(ValueError, match="pixel index -1 is outside"):
        group_by_pixel(np.array([0, -1, 1], np.int32), 4, field)
    with pytest.raises(ValueError, match="one to three"):
        group_by_pixel(np.array([0, 1], np.int32), 4, field)
    with pytest.raises(ValueError, match="one to three"):
        group_by_pixel(np.array([0, 1, 2], np.int32), 4, *[field] * 4)


@pytest.mark.parametrize("band", [1, 2, 5, 64])
@pytest.mark.parametrize("threads", [1, 2, 3])
def test_bands_of_any_size_give_the_same_grouping(monkeypatch, band, threads):
    """The move to bands, then by pixel within each band: lowered here so that small inputs
    span many bands, with a pixel holding more fragments than a band and pixels holding
    none, on one core and on several."""
    monkeypatch.setattr(_group, "BAND_FRAGMENTS", band)
    monkeypatch.setattr(_group, "PARALLEL_MIN", 1)
    monkeypatch.setattr(_group, "host_threads", lambda: threads)
    rng = np.random.default_rng(band * 10 + threads)
    pixel = np.concatenate([rng.integers(0, 40, 300), np.full(20, 7)]).astype(np.int32)
    rng.shuffle(pixel)
    pixel[pixel == 23] = 24  # pixel 23 holds none
    segment = np.arange(pixel.size, dtype=np.int32)
    t = rng.random(pixel.size).astype(np.float32)
    order = np.argsort(pixel, kind="stable")
    sorted_pixel, (seg, got_t) = group_by_pixel(pixel, 45, segment, t)  # pixels 40–44 none
    np.testing.assert_array_equal(sorted_pixel, pixel[order])
    np.testing.assert_array_equal(seg, segment[order])
    np.testing.assert_array_equal(got_t, t[order])


def test_no_fragments():
    sorted_pixel, (seg,) = group_by_pixel(np.zeros(0, np.int32), 4, np.zeros(0, np.int32))
    assert sorted_pixel.shape == seg.shape == (0,)
