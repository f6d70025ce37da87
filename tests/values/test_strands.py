"""Strands validation and tangents (docs/model.md §1)."""

import numpy as np
import pytest

import hairjax as hj
from hairjax._values._strands import tangents


def test_ragged_strands_segments_and_tangents():
    s = hj.Strands.from_list([[[0, 0, 0], [1, 0, 0], [1, 2, 0]], [[5, 5, 5]], [[0, 0, 0], [0, 0, 3]]])
    assert s.num_strands == 3 and s.num_points == 6
    np.testing.assert_array_equal(s.segments(), [[0, 1], [1, 2], [4, 5]])
    np.testing.assert_array_equal(s.strand_of_point, [0, 0, 0, 1, 2, 2])
    t = tangents(s.points, s.offsets)
    np.testing.assert_allclose(t[0], [1, 0, 0])  # one-sided at the root
    np.testing.assert_allclose(t[1], np.array([1, 2, 0]) / np.sqrt(5))  # central difference
    np.testing.assert_allclose(t[2], [0, 1, 0])  # one-sided at the tip
    np.testing.assert_allclose(t[3], [0, 0, 0])  # a one-point strand has no tangent
    np.testing.assert_allclose(t[4:], [[0, 0, 1], [0, 0, 1]])


def test_repeated_points_give_zero_not_nan():
    s = hj.Strands.from_list([[[1, 1, 1], [1, 1, 1], [1, 1, 1]]])
    t = tangents(s.points, s.offsets)
    assert np.all(np.isfinite(t)) and np.all(t == 0)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(alpha=0.0), "alpha"),
        (dict(alpha=1.5), "alpha"),
        (dict(width=-1.0), "width"),
        (dict(points=np.array([[0, 0, np.nan]])), "NaN"),
        (dict(offsets=np.array([0, 0, 1])), "at least one point"),
        (dict(offsets=np.array([0, 2])), "offsets"),
    ],
)
def test_invalid_strands(kwargs, message):
    base = dict(points=np.zeros((1, 3)), offsets=np.array([0, 1]), alpha=0.5, width=1.0)
    base.update(kwargs)
    with pytest.raises(ValueError, match=message):
        hj.Strands(**base)


def test_arrays_are_read_only():
    s = hj.furball(3, 3)
    with pytest.raises(ValueError):
        s.points[0, 0] = 1.0
