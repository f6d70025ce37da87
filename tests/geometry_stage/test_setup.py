"""The geometry set-up's warning for hair that covers no pixel (hairjax/_geometry_stage/_setup.py):
a black image never comes without a word, and a framed one comes without one."""

from __future__ import annotations

import warnings

import jax
import numpy as np
import pytest
from helpers import small_furball_scene

import hairjax as hj
from hairjax._errors import EmptyViewWarning
from hairjax._scene._file import default_scene_path, load_scene
from hairjax._values._strands import Strands


def looking_away():
    """The small fur ball with the camera turned round: the hair is behind it."""
    scene = small_furball_scene(size=16)
    return scene.replace(camera=hj.Camera(eye=(0.0, 0.3, 3.5), target=(0.0, 0.3, 7.0), width=16, height=16))


def test_camera_looking_away_warns_once_with_the_bbox():
    scene = looking_away()
    points = scene.strands.points
    with pytest.warns(EmptyViewWarning) as record:
        image = hj.render(scene)
        hj.render(scene)  # the set-up is cached: no second warning
    assert len(record) == 1
    assert not np.asarray(image)[..., 3].any()
    msg = str(record[0].message)
    for corner in (points.min(axis=0), points.max(axis=0)):
        assert "(" + ", ".join(f"{x:.4g}" for x in corner) + ")" in msg
    assert "eye (0, 0.3, 3.5)" in msg and "target (0, 0.3, 7)" in msg and "fov 40" in msg


def test_hair_beside_the_image_warns():
    # In front of the camera but entirely left of the image.
    scene = small_furball_scene(size=16)
    shifted = scene.replace(strands=scene.strands.transformed(1.0, (-30.0, 0.0, 0.0)))
    with pytest.warns(EmptyViewWarning, match="covers no pixel of the 16x16 image"):
        hj.render(shifted)


def test_warns_under_jit_and_grad_too():
    scene = looking_away()
    with pytest.warns(EmptyViewWarning):
        grad = jax.grad(lambda p: hj.render(scene, p)[..., :3].sum())(scene.params)
    assert np.all(np.asarray(grad.kd) == 0)


def test_framed_scenes_do_not_warn():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        hj.render(small_furball_scene(size=16))
        # The default scene's hair and camera at 24², without its 64 shadow maps (for time:
        # the warning comes from the camera's fragments, which the shadows do not change).
        default = load_scene(default_scene_path())
        small = hj.Camera(**{**vars(default.camera), "width": 24, "height": 24})
        hj.render(default.replace(camera=small, shadows=hj.Shadows("none")))


def test_hair_without_segments_does_not_warn():
    # One-point strands and a zero-length segment draw nothing from any camera: not the
    # camera's fault.
    dots = Strands(
        [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.2, 0.0, 0.0], [0.2, 0.0, 0.0]], [0, 1, 2, 4], 1.0, 1.0
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        hj.render(small_furball_scene(size=16).replace(strands=dots))
