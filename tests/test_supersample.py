"""Camera offsets and supersampling (hairjax/_supersample.py), in both renderers."""

import numpy as np
import pytest
from helpers import refused, small_furball_scene

import hairjax as hj
from hairjax._geometry._projection import camera_view
from hairjax._supersample import shifted, supersample_offsets


def test_offsets_tile_the_pixel():
    assert supersample_offsets(1) == [(0.0, 0.0)]
    assert supersample_offsets(2) == [(-0.25, -0.25), (0.25, -0.25), (-0.25, 0.25), (0.25, 0.25)]
    o = np.asarray(supersample_offsets(4))
    # Cell centres of a 4 × 4 grid over [-½, ½]²: mean zero, spacing 1/4.
    assert o.shape == (16, 2) and np.allclose(o.mean(axis=0), 0.0)
    assert np.allclose(np.unique(o[:, 0]), [-0.375, -0.125, 0.125, 0.375])
    for bad in (0, -1, 1.5, True):
        with pytest.raises(ValueError, match="positive integer"):
            supersample_offsets(bad)


def test_offset_moves_the_projection_of_the_target():
    cam = hj.Camera(eye=(0, 0, 4), width=40, height=30, offset=(0.25, -0.5))
    xy, _ = camera_view(cam).project(np.zeros((1, 3)))
    np.testing.assert_allclose(xy[0], [20.25, 14.5], atol=1e-12)


@pytest.mark.parametrize("offset", [(0.6, 0.0), (0.0, -0.51), (0.1,), "ab"])
def test_offset_must_stay_within_half_a_pixel(offset):
    with refused("offset", "camera.offset"):
        hj.Camera(offset=offset)


def test_supersample_is_the_mean_of_shifted_renders():
    scene = small_furball_scene(strands=60, size=24)
    one = np.asarray(hj.supersample(hj.render, scene, 1))
    np.testing.assert_array_equal(one, np.asarray(hj.render(scene)))
    mean = np.mean([np.asarray(hj.render(shifted(scene, o))) for o in supersample_offsets(2)], axis=0)
    np.testing.assert_allclose(np.asarray(hj.supersample(hj.render, scene, 2)), mean, rtol=0, atol=1e-15)
    assert np.abs(mean - one).max() > 1e-3  # the shifted renders do differ


def test_supersampled_image_is_differentiable():
    import jax

    scene = small_furball_scene(strands=30, size=16, shadows="none")

    def loss(ks):
        p = hj.ShadingParams(kd=(0.6, 0.4, 0.3), ks=ks, shininess=20.0, kappa=0.8, ambient=0.05)
        return hj.supersample(lambda sc: hj.render(sc, p), scene, 2)[..., :3].sum()

    g = float(jax.grad(loss)(0.4))
    # The image is linear in Ks, so the central difference is exact up to rounding.
    fd = (float(loss(0.5)) - float(loss(0.3))) / 0.2
    assert g > 0 and abs(g - fd) <= 1e-9 * abs(fd)


def test_gl_follows_the_offset(gl):
    from hairjax.gl import render_gl

    scene = small_furball_scene(strands=60, size=32)
    moved = shifted(scene, (0.5, 0.25))
    gl_moved, jax_moved = render_gl(moved).image, np.asarray(hj.render(moved))
    change = np.sqrt(np.mean((gl_moved - render_gl(scene).image) ** 2))
    agree = np.sqrt(np.mean((gl_moved - jax_moved) ** 2))
    # The shift changes the GL image by far more than GL and JAX differ on the shifted scene
    # (their cross-check, tests/gl/test_renderer.py, explains each pixel that differs by > 1e-4).
    assert change > 1e-2 and agree < 0.05 * change
