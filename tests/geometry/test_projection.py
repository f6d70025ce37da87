"""Camera conventions (docs/model.md §2)."""

import numpy as np

from hairjax import Camera
from hairjax._geometry._projection import camera_view


def test_target_at_centre_up_is_up_right_is_right():
    cam = Camera(eye=(1.0, 2.0, 5.0), target=(0.5, 1.0, -1.0), up=(0, 1, 0), fov=50.0, width=64, height=48)
    view = camera_view(cam)
    xy, depth = view.project(np.array([cam.target]))
    np.testing.assert_allclose(xy[0], [32.0, 24.0], atol=1e-12)
    np.testing.assert_allclose(depth[0], np.linalg.norm(np.subtract(cam.target, cam.eye)))
    above = np.asarray(cam.target) + 0.1 * view.up
    right = np.asarray(cam.target) + 0.1 * view.right
    xy2, _ = view.project(np.stack([above, right]))
    assert xy2[0, 1] < 24.0  # up in the world → smaller row index
    assert xy2[1, 0] > 32.0


def test_vertical_field_of_view():
    cam = Camera(eye=(0, 0, 0), target=(0, 0, -1), fov=90.0, width=100, height=100)
    # At fov 90° a point at 45° above the axis lands on the top edge (y = 0).
    xy, _ = camera_view(cam).project(np.array([[0.0, 2.0, -2.0]]))
    np.testing.assert_allclose(xy[0], [50.0, 0.0], atol=1e-12)


def test_pixel_rays_go_through_pixel_centres():
    cam = Camera(eye=(0, 0, 3), target=(0, 0, 0), fov=30.0, width=8, height=6)
    view = camera_view(cam)
    o, d = view.pixel_rays()
    pts = o + 2.0 * d
    xy, _ = view.project(pts)
    j, i = np.mgrid[0:6, 0:8]
    np.testing.assert_allclose(xy[:, 0], i.ravel() + 0.5, atol=1e-9)
    np.testing.assert_allclose(xy[:, 1], j.ravel() + 0.5, atol=1e-9)
