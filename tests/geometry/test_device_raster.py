"""The set-up's raster and grouping as XLA programs (hairjax/_geometry/_device_raster.py):
the same fragments as the host's compiled loops, in the same order. Run here on the CPU
device (`placement="device"`), which executes the programs a GPU would."""

import dataclasses
import os

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import first_then_slow
from hypothesis import given, settings
from hypothesis import strategies as st

import hairjax as hj
from hairjax._errors import SceneTooLarge
from hairjax._geometry import _device_raster
from hairjax._geometry._device_raster import (
    device_candidates,
    group_on_device,
    rasterize_on_device,
)
from hairjax._geometry._group import group_by_pixel
from hairjax._geometry._placement import PLACEMENT_VARIABLE, default_placement, placement_of
from hairjax._geometry._raster import rasterize
from hairjax._geometry_stage._setup import prepare
from hairjax._geometry_stage._stage import geometry_stage

W, H = 90, 70


def _segments(seed, n=400, snap=False):
    """Segments on and off the image, some of length 0, some at constant depth, ribbons of
    varying width at their two ends. `snap`: ends on pixel centres, so that candidates
    fall exactly on a segment's ends (s = 0 and s = L) and on its ribbon's edges."""
    rng = np.random.default_rng(seed)
    xy0 = rng.uniform(-15, 105, (n, 2))
    xy1 = xy0 + rng.normal(0, 7, (n, 2))
    if snap:
        xy0, xy1 = np.floor(xy0) + 0.5, np.floor(xy1) + 0.5
    xy1[::23] = xy0[::23]  # length 0: cover nothing
    z0 = rng.uniform(1, 5, n)
    z1 = z0 + rng.normal(0, 0.3, n)
    z1[::5] = z0[::5]  # constant depth: z kept exactly
    width = rng.integers(1, 4, (n, 2)).astype(float) if snap else rng.uniform(0.2, 3.5, (n, 2))
    return xy0, xy1, z0, z1, width


def _on_device(xy0, xy1, z0, z1, width, perspective, labels=None):
    return rasterize_on_device(xy0, xy1, z0, z1, width, W, H, perspective, labels=labels)


@pytest.mark.parametrize("perspective", [True, False])
@pytest.mark.parametrize("seed, snap", [(0, False), (1, False), (4, True)])
def test_the_device_raster_writes_the_host_loops_fragments(seed, snap, perspective):
    segs = _segments(seed, snap=snap)
    host = rasterize(*segs, W, H, perspective)
    device = _on_device(*segs, perspective)
    assert host.size > 1000  # the case covers pixels
    for name in ("pixel", "segment", "coverage", "t"):  # the same arithmetic, in the same order
        np.testing.assert_array_equal(np.asarray(getattr(device, name)), getattr(host, name), err_msg=name)
    # Perspective depth, 1/((1 − t)/z₀ + t/z₁): the two compilers contract its
    # multiply-adds differently (BENCHMARKS.md "rasterize"); each of its four rounded
    # operations may then round once differently: 4 ulps at most.
    eps = np.finfo(host.depth.dtype).eps
    rtol = 4 * eps if perspective else 0
    np.testing.assert_allclose(np.asarray(device.depth), host.depth, rtol=rtol, atol=0)


def test_labels_name_the_fragments_segments():
    segs = _segments(2)
    labels = np.arange(len(segs[0]), dtype=np.int32) * 3 + 7
    host = rasterize(*segs, W, H, True)
    device = _on_device(*segs, True, labels=labels)
    np.testing.assert_array_equal(np.asarray(device.segment), labels[host.segment])


def test_no_segments_and_nothing_covered():
    empty = np.zeros((0, 2))
    none = _on_device(empty, empty, np.ones(0), np.ones(0), np.ones(0), True)
    assert none.size == 0
    outside = np.array([[-50.0, -50.0]])
    assert _on_device(outside, outside + 3, np.ones(1), np.ones(1), np.ones(1), True).size == 0


@given(st.integers(1, 40), st.lists(st.integers(0, 10**6), max_size=300), st.integers(0, 2**31 - 1))
@settings(max_examples=40, deadline=None)
def test_grouping_on_the_device_is_the_hosts(n_pixels, raw, seed):
    """The kept entries grouped by pixel in their given order: the host's counting sort."""
    pixel = (np.asarray(raw, np.int64) % n_pixels).astype(np.int32)
    keep = np.random.default_rng(seed).random(pixel.size) < 0.7
    segment = np.arange(pixel.size, dtype=np.int32)
    value = np.linspace(0, 1, pixel.size)
    want_pixel, (want_segment, want_value) = group_by_pixel(pixel[keep], n_pixels, segment[keep], value[keep])
    args = jnp.asarray(pixel), jnp.asarray(keep), n_pixels, jnp.asarray(segment), jnp.asarray(value)
    got_pixel, (got_segment, got_value), count = group_on_device(*args)
    assert count == want_pixel.size
    np.testing.assert_array_equal(np.asarray(got_pixel), want_pixel)
    np.testing.assert_array_equal(np.asarray(got_segment), want_segment)
    np.testing.assert_array_equal(np.asarray(got_value), want_value)
    # Padded to a capacity: the same entries, then pixel n_pixels and zeros.
    size = count + 5 + pixel.size  # beyond the inputs' length too
    padded_pixel, (padded_segment, padded_value), _ = group_on_device(*args, capacity=lambda n: size)
    np.testing.assert_array_equal(
        np.asarray(padded_pixel), np.r_[want_pixel, np.full(size - count, n_pixels)]
    )
    np.testing.assert_array_equal(np.asarray(padded_segment), np.r_[want_segment, np.zeros(size - count)])
    np.testing.assert_array_equal(np.asarray(padded_value), np.r_[want_value, np.zeros(size - count)])


def test_the_default_placement_follows_the_environment_and_nothing_writes_it(monkeypatch):
    monkeypatch.delenv(PLACEMENT_VARIABLE, raising=False)
    assert default_placement() == ("host" if jax.default_backend() == "cpu" else "device")
    for where in ("device", "host"):
        monkeypatch.setenv(PLACEMENT_VARIABLE, where)
        assert default_placement() == where == placement_of(None)
        assert placement_of("host") == "host" and placement_of("device") == "device"
    monkeypatch.setenv(PLACEMENT_VARIABLE, "gpu")
    with pytest.raises(ValueError, match="auto, host or device"):
        default_placement()
    with pytest.raises(ValueError, match="'host' or 'device'"):
        placement_of("auto")
    monkeypatch.setenv(PLACEMENT_VARIABLE, "host")
    np.asarray(hj.render(_scene("default"), placement="device"))
    assert os.environ[PLACEMENT_VARIABLE] == "host"


def test_one_scene_under_both_placements_gets_each_placements_own_set_up():
    """The per-scene cache keys on the placement: the same scene object set up on the host
    and then on the device holds both, and each call gets its own (NumPy fragments from
    the loops, JAX arrays from the XLA programs), with the same image."""
    scene = _scene("default")
    host_image = np.asarray(hj.render(scene, placement="host"))
    device_image = np.asarray(hj.render(scene, placement="device"))
    host, device = prepare(scene, placement="host"), prepare(scene, placement="device")
    assert isinstance(host.frag_pixel, np.ndarray) and isinstance(device.frag_pixel, jax.Array)
    assert prepare(scene, placement="host") is host and prepare(scene, placement="device") is device
    assert geometry_stage(scene, placement="host") is not geometry_stage(scene, placement="device")
    np.testing.assert_array_equal(np.asarray(device.frag_pixel), host.frag_pixel)
    np.testing.assert_allclose(device_image, host_image, rtol=0, atol=1e-5)  # docs/model.md §5's bound


def test_a_raster_beyond_the_devices_memory_is_refused_before_it_is_allocated(monkeypatch):
    monkeypatch.setattr(_device_raster, "_free_bytes", lambda: 1000)
    with pytest.raises(SceneTooLarge, match=r"candidate fragments, which need .* GiB .* on the device"):
        device_candidates(*_segments(3), W, H, True, depth=False)


def _scene(name):
    """The scene at 96 × 72 with 8 opacity maps of 64² (its light raster a sixteenth of
    the default's: this file's time), or its own shadows where they are not opacity maps."""
    scene = hj.load_scene(name if name.endswith(".toml") else hj.default_scene_path())
    scene = scene.replace(camera=dataclasses.replace(scene.camera, width=96, height=72))
    if scene.shadows.method == "opacity-maps":
        scene = scene.replace(shadows=hj.Shadows("opacity-maps", 8, 64))
    return scene


SCENES = {
    "default": "default",
    "occluder": "experiments/scenes/occluder.toml",
    "point light": "experiments/scenes/point_light.toml",
    "alpha texture": "experiments/scenes/scheuermann.toml",
    "hair patches": "experiments/scenes/patches.toml",
}


@pytest.mark.parametrize("name", first_then_slow(SCENES))
def test_the_set_up_on_the_device_gives_the_hosts_fragments_and_image(name):
    """Each scene set up and rendered twice, on the host and on the device (fresh scene
    objects: the set-up is cached per scene)."""
    results = {}
    for where in ("host", "device"):
        scene = _scene(SCENES[name])
        results[where] = prepare(scene, placement=where), np.asarray(hj.render(scene, placement=where))
    (host, host_image), (device, device_image) = results["host"], results["device"]
    assert isinstance(device.frag_pixel, jax.Array) and isinstance(host.frag_pixel, np.ndarray)
    assert host.frag_pixel.size > 100
    for field in ("frag_pixel", "frag_i0", "frag_t"):
        np.testing.assert_array_equal(np.asarray(getattr(device, field)), getattr(host, field), err_msg=field)
    # The alpha texture's factor: on the host float64 times the fragment's coverage, on
    # the device rounded to its precision first (1 ulp of a coverage ≤ 1).
    eps = np.finfo(host.frag_coverage.dtype).eps
    np.testing.assert_allclose(np.asarray(device.frag_coverage), host.frag_coverage, rtol=0, atol=eps)
    if host.shadow is not None and hasattr(host.shadow, "frag_cell"):  # the light's raster too
        np.testing.assert_array_equal(np.asarray(device.shadow.frag_cell), host.shadow.frag_cell)
    # The bound for the images of the two set-ups: 1e-5 (experiments/README.md row 19; the
    # fragments are the same, docs/model.md §5, "On an accelerator"). Here they agree to
    # rounding: the same fragments, composited by the same programs.
    np.testing.assert_allclose(device_image, host_image, rtol=0, atol=1e-5)


def test_an_empty_view_warns_on_the_device_too():
    scene = _scene("default")
    away = dataclasses.replace(scene.camera, target=tuple(2 * np.asarray(scene.camera.eye)))
    with pytest.warns(hj.EmptyViewWarning):
        prepare(scene.replace(camera=away), placement="device")
