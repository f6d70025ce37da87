"""The strands on the GPU (`hairjax/gl/_buffers.py`): uploaded once per scene, the same
images from every later render, Ω and V back at their defaults where a render does not
write them, and the buffers released with the cache entry."""

import gc

import numpy as np
from helpers import small_furball_scene

from hairjax._cache import forget
from hairjax.gl import _buffers, render_gl


def test_a_scene_is_uploaded_once_and_renders_the_same(gl, monkeypatch):
    uploads = []
    original = _buffers.Strands.__init__

    def counting(self, ctx, scene):
        uploads.append(scene)
        original(self, ctx, scene)

    monkeypatch.setattr(_buffers.Strands, "__init__", counting)
    scene = small_furball_scene(strands=60, size=32, shadows="opacity-maps")
    first = render_gl(scene)
    second = render_gl(scene)
    assert len(uploads) == 1  # the second render drew from the first's buffers
    np.testing.assert_array_equal(first.image, second.image)
    np.testing.assert_array_equal(first.omega, second.omega)
    other = scene.replace()  # another scene object: its own upload
    np.testing.assert_array_equal(render_gl(other).image, first.image)
    assert len(uploads) == 2


def test_omega_goes_back_to_zero_when_a_render_does_not_write_it(gl):
    """A render given Ω leaves it in the buffer; the next render of the scene, without
    shadows, must see Ω = 0 again, as a fresh upload does."""
    scene = small_furball_scene(strands=60, size=32, shadows="none")
    fresh = render_gl(scene.replace()).image
    given = render_gl(scene, omega=np.full(scene.strands.num_points, 3.0)).image
    assert np.abs(given - fresh).max() > 1e-3  # Ω = 3 darkened it
    np.testing.assert_array_equal(render_gl(scene).image, fresh)


def test_the_buffers_go_with_the_cache_entry(gl):
    scene = small_furball_scene(strands=60, size=32, shadows="none")
    render_gl(scene)
    strands = _buffers.resident_strands(gl, scene)
    release = strands._release
    assert release.alive
    del strands
    forget(scene)  # the entry goes: the Strands object is collected, its buffers released
    gc.collect()
    assert not release.alive
