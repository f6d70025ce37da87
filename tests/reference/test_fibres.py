"""The strands as Mitsuba curves (hairjax/_reference/_fibres.py): radii from the ribbons'
world width, what hairjax does not draw left out, ends pulled in by their radius, and the
curve file's text. NumPy only: no Mitsuba needed."""

from __future__ import annotations

import numpy as np

import hairjax as hj
from hairjax._reference._fibres import END_TRIM_LIMIT, curve_file_text, fibre_curves

CAMERA = hj.Camera(eye=(0.0, 0.0, 5.0), target=(0.0, 0.0, 0.0), fov=40.0, width=64, height=48)


def _strands(points_list, width, units):
    return hj.Strands.from_list(points_list, width=width).replace(width_units=units)


def test_world_width_is_the_diameter_and_ends_are_pulled_in_by_the_radius():
    strands = _strands([[(0, 0, 0), (1, 0, 0), (2, 0, 0)]], 0.2, "world")
    points, offsets = fibre_curves(strands, CAMERA)
    np.testing.assert_array_equal(offsets, [0, 3])
    np.testing.assert_allclose(points[:, 3], 0.1)
    np.testing.assert_allclose(points[:, :3], [(0.1, 0, 0), (1, 0, 0), (1.9, 0, 0)])


def test_pixel_width_becomes_w_d_over_f_at_each_point():
    """A w-pixel ribbon is a fibre of diameter w·D/f: as wide on screen at every depth."""
    strands = _strands([[(0, 0, 1.0), (0.5, 0, -2.0), (1.0, 0, -6.0)]], 1.5, "pixels")
    view = hj.camera_view(CAMERA)
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
    np.testing.assert_allclose(points[offsets[1] : offsets[2], 2], [0.005, 0.995])


def test_a_short_piece_keeps_a_third_between_its_ends():
    strands = _strands([[(0, 0, 0), (0.3, 0, 0)]], 2.0, "world")  # radius 1 > the segment
    points, _ = fibre_curves(strands, CAMERA)
    np.testing.assert_allclose(points[:, 0], [0.3 * END_TRIM_LIMIT, 0.3 * (1 - END_TRIM_LIMIT)])


def test_the_curve_file_has_a_line_per_point_and_a_blank_line_between_curves():
    points = np.array([[0, 0, 0, 0.1], [1, 0, 0, 0.1], [0, 1, 0, 0.2], [0, 2, 0, 0.2], [0, 3, 0, 1 / 3]])
    text = curve_file_text(points, np.array([0, 2, 5]))
    blocks = text.strip("\n").split("\n\n")
    assert [len(b.splitlines()) for b in blocks] == [2, 3]
    read = np.array([[float(v) for v in line.split()] for b in blocks for line in b.splitlines()])
    np.testing.assert_allclose(read, points, rtol=1e-8)
    assert np.float32(read[-1, 3]) == np.float32(1 / 3)  # 9 digits round-trip float32
