"""Ribbon coverage and fragments (docs/model.md §5)."""

import numpy as np
import pytest

from hairjax._raster import rasterize, ribbon_coverage


def image(frags, w, h, weights=None):
    weights = frags.coverage if weights is None else weights
    return np.bincount(frags.pixel, weights, minlength=w * h).reshape(h, w)


def test_coverage_by_hand():
    # Width 1: box [d − ½, d + ½] ∩ [−½, ½] has length 1 − d for 0 ≤ d ≤ 1.
    np.testing.assert_allclose(ribbon_coverage(np.array([0.0, 0.25, 0.5, 1.0, 1.5]), np.ones(5)),
                               [1.0, 0.75, 0.5, 0.0, 0.0])
    # Width 0.25: fully inside the box up to d = 0.375, then shrinking to 0 at 0.625.
    np.testing.assert_allclose(ribbon_coverage(np.array([0.0, 0.375, 0.5, 0.625]), np.full(4, 0.25)),
                               [0.25, 0.25, 0.125, 0.0])
    # Width 3: the box is inside the ribbon for d ≤ 1.
    np.testing.assert_allclose(ribbon_coverage(np.array([0.0, 1.0, 1.5, 2.0]), np.full(4, 3.0)),
                               [1.0, 1.0, 0.5, 0.0])


def test_horizontal_line_through_pixel_centres():
    # y = 3.5 runs through row 3's centres; x ∈ [2.2, 7.9) contains centres 2.5 … 7.5.
    f = rasterize(np.array([[2.2, 3.5]]), np.array([[7.9, 3.5]]), np.ones(1), np.ones(1),
                  np.ones(1), 10, 8, False)
    img = image(f, 10, 8)
    expected = np.zeros((8, 10))
    expected[3, 2:8] = 1.0
    np.testing.assert_allclose(img, expected, atol=1e-12)
    # t = s/L at the centres.
    np.testing.assert_allclose(np.sort(f.t), (np.arange(2, 8) + 0.5 - 2.2) / 5.7, rtol=1e-12)


def test_line_between_rows_splits_coverage():
    # y = 4.0: centres of rows 3 and 4 are ½ away, each covered ½.
    f = rasterize(np.array([[0.0, 4.0]]), np.array([[6.0, 4.0]]), np.ones(1), np.ones(1),
                  np.ones(1), 6, 8, False)
    img = image(f, 6, 8)
    np.testing.assert_allclose(img[3], 0.5)
    np.testing.assert_allclose(img[4], 0.5)
    assert img.sum() == pytest.approx(6.0)


@pytest.mark.parametrize("direction", [(27.4, 21.1), (-5.3, 30.2), (12.0, -12.0), (-30.0, -2.0)])
def test_straight_strand_as_one_or_eight_segments(direction):
    """Same fragments for 1 and 8 collinear segments: no double-covered joints, no gaps."""
    p0 = np.array([32.3, 31.1])
    p1 = p0 + np.array(direction)
    pts = p0 + np.linspace(0, 1, 9)[:, None] * (p1 - p0)
    w, h = 64, 64
    one = rasterize(p0[None], p1[None], np.ones(1), np.ones(1), np.ones(1), w, h, True)
    eight = rasterize(pts[:-1], pts[1:], np.ones(8), np.ones(8), np.ones(8), w, h, True)
    # Each pixel appears once per drawing (no pixel drawn by two neighbouring segments).
    assert np.bincount(eight.pixel).max() == 1
    assert np.array_equal(np.sort(one.pixel), np.sort(eight.pixel))
    # Coverage equal up to the rounding of each segment's own direction (float64).
    np.testing.assert_allclose(image(eight, w, h), image(one, w, h), atol=1e-12)
    assert image(one, w, h).sum() > 0.9 * np.hypot(*direction)


def test_zero_length_and_offscreen_segments_draw_nothing():
    xy = np.array([[5.0, 5.0], [-50.0, -50.0]])
    xy1 = np.array([[5.0, 5.0], [-40.0, -45.0]])
    f = rasterize(xy, xy1, np.ones(2), np.ones(2), np.ones(2), 16, 16, True)
    assert f.size == 0


def test_fragments_stay_inside_the_image_and_cover_positive():
    rng = np.random.default_rng(1)
    a = rng.uniform(-10, 40, (200, 2))
    b = a + rng.normal(0, 8, (200, 2))
    w = rng.uniform(0.25, 8, 200)
    f = rasterize(a, b, np.ones(200), np.ones(200), w, 30, 20, True)
    assert f.pixel.min() >= 0 and f.pixel.max() < 600
    assert np.all((f.coverage > 0) & (f.coverage <= 1))
    assert np.all((f.t >= 0) & (f.t < 1))


def test_perspective_correct_depth():
    # 1/z is linear in t: at t = ½ between z = 1 and z = 3, z = 1/(½ + 1/6) = 1.5.
    f = rasterize(np.array([[0.0, 0.5]]), np.array([[2.0, 0.5]]), np.array([1.0]),
                  np.array([3.0]), np.ones(1), 2, 1, True)
    # Centres at x = 0.5, 1.5: t = ¼, ¾.
    np.testing.assert_allclose(np.sort(f.depth), [1 / (0.75 + 0.25 / 3), 1 / (0.25 + 0.75 / 3)])
