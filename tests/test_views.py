"""Batched views and lights (`hairjax.render_views`): each view equals its own render, and
the view axis is sharded over the devices."""

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import hairjax as hj

REPO = Path(__file__).resolve().parents[1]


def small_scene(**changes):
    scene = hj.Scene(
        strands=hj.furball(300, 8, seed=0),
        camera=hj.Camera(eye=(0.0, 0.3, 4.2), target=(0.0, 0.0, 0.0), fov=40.0, width=40, height=32),
        shadows=hj.Shadows("opacity-maps", 8, 32),
    )
    return scene.replace(**changes)


def orbit(n, w=40, h=32):
    return [
        hj.Camera(eye=(4.2 * np.sin(a), 0.3, 4.2 * np.cos(a)), target=(0, 0, 0), fov=40.0, width=w, height=h)
        for a in np.linspace(0.0, 2.0, n)
    ]


def test_each_view_equals_its_own_render_with_an_occluder():
    # Three views (not a power of two: the fragment arrays of each view are padded), the
    # occluder covering different pixels in each. The views' arithmetic is the single
    # render's, plus padded zeros: 1e-12 allows float64 summation order only.
    scene = small_scene(occluder=hj.Occluder(center=(0.0, 0.0, 0.0), radius=0.4))
    cameras = orbit(3)
    images = np.asarray(hj.render_views(scene, cameras))
    assert images.shape == (3, 32, 40, 4)
    for i, cam in enumerate(cameras):
        one = np.asarray(hj.render(scene.replace(camera=cam)))
        np.testing.assert_allclose(images[i], one, rtol=0, atol=1e-12)
    assert np.abs(images[0] - images[2]).max() > 0.05  # the views differ


def test_lights_batch_and_pair_with_cameras():
    scene = small_scene()
    lights = [
        hj.Light(direction=(-1.0, -1.0, -0.5)),
        hj.Light(direction=(1.0, -1.0, -1.0), color=(0.5, 0.8, 1.0)),
    ]
    images = np.asarray(hj.render_views(scene, lights=lights))
    for i, light in enumerate(lights):
        one = np.asarray(hj.render(scene.replace(light=light)))
        np.testing.assert_allclose(images[i], one, rtol=0, atol=1e-12)
    cameras = orbit(2)
    paired = np.asarray(hj.render_views(scene, cameras, lights=lights))
    one = np.asarray(hj.render(scene.replace(camera=cameras[1], light=lights[1])))
    np.testing.assert_allclose(paired[1], one, rtol=0, atol=1e-12)


def test_bad_batches_are_refused_in_one_line():
    scene = small_scene()
    with pytest.raises(ValueError, match="camera 1 is 20x16, the scene's 40x32"):
        hj.render_views(scene, [orbit(1)[0], orbit(1, 20, 16)[0]])
    with pytest.raises(ValueError, match="2 cameras and 1 lights"):
        hj.render_views(scene, orbit(2), lights=[hj.Light()])
    with pytest.raises(ValueError, match="at least one view"):
        hj.render_views(scene, [])
    with pytest.raises(ValueError, match="needs cameras, lights or both"):
        hj.render_views(scene)


SHARDED = textwrap.dedent(
    """
    import jax
    jax.config.update("jax_enable_x64", True)
    import numpy as np
    import hairjax as hj
    from tests.test_views import orbit, small_scene

    assert len(jax.devices()) == 4, jax.devices()
    scene = small_scene()
    cameras = orbit(4)
    images = hj.render_views(scene, cameras)
    assert len(images.sharding.device_set) == 4, images.sharding
    one = hj.render_views(scene, cameras, devices=jax.devices()[:1])
    assert len(one.sharding.device_set) == 1
    images, one = np.asarray(images), np.asarray(one)
    assert np.array_equal(images, one), np.abs(images - one).max()
    print("sharded ok")
    """
)


def test_views_are_sharded_over_four_host_devices():
    # XLA's device count is fixed when JAX starts, so four forced host devices need a
    # fresh process. The views' images must be identical to the same batch on one device.
    env = dict(os.environ, XLA_FLAGS="--xla_force_host_platform_device_count=4", PYTHONPATH=str(REPO))
    run = subprocess.run(
        [sys.executable, "-c", SHARDED], cwd=REPO, env=env, capture_output=True, text=True, timeout=300
    )
    assert run.returncode == 0, run.stderr[-3000:]
    assert "sharded ok" in run.stdout
