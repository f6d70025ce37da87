"""Visibility ordering (docs/model.md §4, kim-2003 §3)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hairjax._ordering import bin_index, draw_order, segment_depth, stable_argsort_uint32


def test_bin_formula_by_hand():
    # Dmin = 2, Dmax = 6, N = 4: ε = 4/8 = 0.5, i = ⌊4 (D − 2)/4.5⌋.
    depth = np.array([2.0, 3.0, 4.25, 5.0, 6.0, 3.125])
    # 4·0/4.5 = 0, 4·1/4.5 = 0.89, 4·2.25/4.5 = 2, 4·3/4.5 = 2.67, 4·4/4.5 = 3.56, 4·1.125/4.5 = 1
    expected = [0, 0, 2, 2, 3, 1]
    np.testing.assert_array_equal(bin_index(depth, 4), expected)


def test_degenerate_depth_range_is_one_bin():
    np.testing.assert_array_equal(bin_index(np.full(5, 3.7), 16), np.zeros(5))
    assert bin_index(np.zeros(0), 8).shape == (0,)


@given(st.lists(st.floats(-1e6, 1e6), min_size=1, max_size=50), st.integers(1, 5000))
@settings(max_examples=200, deadline=None)
def test_bins_in_range_and_monotone(depths, n):
    depth = np.asarray(depths)
    i = bin_index(depth, n)
    assert i.min() >= 0 and i.max() < n
    order = np.argsort(depth)
    assert np.all(np.diff(i[order]) >= 0)


def test_farther_endpoint_decides():
    depth = np.array([1.0, 5.0, 2.0])
    segs = np.array([[0, 1], [1, 2], [0, 2]])
    np.testing.assert_array_equal(segment_depth(depth, segs), [5.0, 5.0, 2.0])


def test_draw_order_far_bins_first_index_within_bin():
    seg_depth = np.array([1.0, 9.0, 1.1, 8.9, 5.0])
    # Two bins split at ~5.05: {0, 2, 4} near, {1, 3} far.
    np.testing.assert_array_equal(draw_order(seg_depth, "bins", 2), [1, 3, 0, 2, 4])
    np.testing.assert_array_equal(draw_order(seg_depth, "exact"), [1, 3, 4, 2, 0])
    np.testing.assert_array_equal(draw_order(seg_depth, "none"), [0, 1, 2, 3, 4])
    with pytest.raises(ValueError):
        draw_order(seg_depth, "random")


@given(st.lists(st.integers(0, 2**32 - 1), max_size=300))
@settings(max_examples=100, deadline=None)
def test_radix_argsort_is_a_stable_sort(keys):
    keys = np.asarray(keys, dtype=np.int64)
    np.testing.assert_array_equal(stable_argsort_uint32(keys), np.argsort(keys, kind="stable"))
