"""The strands as Mitsuba curves (hairjax/_reference/_fibres.py): radii from the ribbons'
world width, what hairjax does not draw left out, the B-spline that is the polyline, and
the curve file's text. NumPy only: no Mitsuba needed."""

from __future__ import annotations

import numpy as np

import hairjax as hj
from hairjax._reference._fibres import SPREAD, bspline_control_points, curve_file_text, fibre_curves

CAMERA = hj.Camera(eye=(0.0, 0.0, 5.0), target=(0.0, 0.0, 0.0), fov=40.0, width=64, height=48)


def _strands(points_list, width, units):
    return hj.Strands.from_list(points_list, width=width).replace(width_units=units)


def test_world_width_is_the_diameter_and_the_ends_are_the_strands():
    strands = _strands([[(0, 0, 0), (1, 0, 0), (2, 0, 0)]], 0.2, "world")
    points, offsets = fibre_curves(strands, CAMERA)
    np.testing.assert_array_equal(offsets, [0, 3])
    np.testing.assert_allclose(points[:, 3], 0.1)
    # A bsplinecurve has no end caps: the fibre ends where the ribbon does, at the points.
    np.testing.assert_allclose(points[:, :3], [(0, 0, 0), (1, 0, 0), (2, 0, 0)])


def test_pixel_width_becomes_w_d_over_f_at_each_point():
    """A w-pixel ribbon is a fibre of diameter w·D/f: as wide on screen at every depth."""
    strands = _strands([[(0, 0, 1.0), (0.5, 0, -2.0), (1.0, 0, -6.0)]], 1.5, "pixels")
    view = hj.experimental.camera_view(CAMERA)
    points, _ = fibre_curves(strands, CAMERA)
    _, depth = view.project(points[:, :3])
    np.testing.assert_allclose(2 * points[:, 3] * view.focal / depth, 1.5, rtol=1e-12)


def test_what_hairjax_does_not_draw_is_left_out():
    """Repeated points join their neighbours (no piece is cut there), a segment reaching the
    near plane cuts the strand, a one-point strand or piece is dropped."""
    near = CAMERA.near
    strands = _strands(
        [
            [(0, 0, 0), (1, 0, 0), (1, 0, 0), (2, 0, 0)],  # a repeated point: one piece
            [(0, 1, 0)],  # one point: nothing
            [(0, -1, 0), (0, -1, 1), (0, -1, 5.0 - near / 2), (0, -1, 1.5), (0, -1, 1), (0.5, -1, 1)],
        ],
        0.01,
        "world",
    )
    points, offsets = fibre_curves(strands, CAMERA)
    assert np.diff(offsets).tolist() == [3, 2, 3]  # the third strand cut around the eye
    np.testing.assert_allclose(points[offsets[1] : offsets[2], 2], [0.0, 1.0])


def _uniform_cubic_bspline(control: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The uniform cubic B-spline of `control` at parameters t in [0, len − 3): piece i
    weighs control points i … i + 3 by the basis ((1−u)³, 3u³ − 6u² + 4, −3u³ + 3u² + 3u + 1,
    u³)/6 (de Boor; the curve Mitsuba's bsplinecurve draws)."""
    i = np.minimum(np.floor(t).astype(int), len(control) - 4)
    u = (t - i)[:, None]
    w = [(1 - u) ** 3, 3 * u**3 - 6 * u**2 + 4, -3 * u**3 + 3 * u**2 + 3 * u + 1, u**3]
    return sum(wk * control[i + k] for k, wk in enumerate(w)) / 6.0


def test_the_b_spline_is_the_polyline():
    """Evaluated as a B-spline, the control points trace the polyline: from by its first
    point to by its last, straight along each segment with the radius interpolated there, but within
    SPREAD of a segment's length of each corner, where the curve rounds it by no more than
    that (module docstring of _fibres.py)."""
    strands = _strands([[(0, 0, 0), (1, 0.5, 0), (1.5, 2, 1), (1, 3, 1)]], 0.2, "world")
    points, offsets = fibre_curves(strands, CAMERA)
    points[:, 3] = [0.1, 0.3, 0.2, 0.05]  # radii that change, to see them interpolated
    control, control_offsets = bspline_control_points(points, offsets)
    np.testing.assert_array_equal(control_offsets, 3 * offsets)
    curve = _uniform_cubic_bspline(control, np.linspace(0.0, len(control) - 3, 4001))
    longest = np.max(np.linalg.norm(np.diff(points[:, :3], axis=0), axis=1))
    # It starts and ends a sixth of the spread inside the end points, on the segment.
    assert np.linalg.norm(curve[0] - points[0]) < SPREAD * longest / 6 + 1e-12
    assert np.linalg.norm(curve[-1] - points[-1]) < SPREAD * longest / 6 + 1e-12
    for p in points:  # the curve passes by every point, within the corner's rounding
        assert np.min(np.linalg.norm(curve[:, :3] - p[:3], axis=1)) < SPREAD / 4 * longest
    a, b = points[:-1], points[1:]
    step = b[:, :3] - a[:, :3]
    for c in curve:  # every curve point lies on a segment, its radius interpolated there
        s = np.clip(np.sum((c[:3] - a[:, :3]) * step, axis=1) / np.sum(step * step, axis=1), 0, 1)
        near = a + s[:, None] * (b - a)
        k = np.argmin(np.linalg.norm(near[:, :3] - c[:3], axis=1))
        corner = np.min(np.linalg.norm(points[1:-1, :3] - c[:3], axis=1))
        if corner > longest / 4:  # a spline piece reaches a sixth of a segment: straight here
            np.testing.assert_allclose(c, near[k], atol=1e-12)
        else:  # near a corner: rounded, off the polyline by at most a quarter of the spread
            assert np.linalg.norm(c - near[k]) < SPREAD / 4 * longest


def test_the_curve_file_has_a_line_per_point_and_a_blank_line_between_curves():
    points = np.array([[0, 0, 0, 0.1], [1, 0, 0, 0.1], [0, 1, 0, 0.2], [0, 2, 0, 0.2], [0, 3, 0, 1 / 3]])
    text = curve_file_text(points, np.array([0, 2, 5]))
    blocks = text.strip("\n").split("\n\n")
    assert [len(b.splitlines()) for b in blocks] == [2, 3]
    read = np.array([[float(v) for v in line.split()] for b in blocks for line in b.splitlines()])
    np.testing.assert_allclose(read, points, rtol=1e-8)
    assert np.float32(read[-1, 3]) == np.float32(1 / 3)  # 9 digits round-trip float32
