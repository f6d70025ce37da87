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


def test_gl_work_is_counted_and_shows_the_resident_strands(gl):
    """`counted_gl_work`: a render draws, binds its targets, reads its image back; the
    scene's second render uploads less, its strands being resident; and moderngl's methods
    are themselves again after the block."""
    import moderngl

    from hairjax.gl._work import counted_gl_work

    original = moderngl.VertexArray.render
    scene = small_furball_scene(strands=60, size=32, shadows="opacity-maps", maps=4)
    with counted_gl_work() as first:
        image = render_gl(scene).image
    with counted_gl_work() as second:
        render_gl(scene)
    assert moderngl.VertexArray.render is original
    # One ribbon draw per opacity map at least, and the camera's; its RGBA image read back.
    assert first.draws >= scene.shadows.maps + 1 and first.binds >= 2
    assert first.read_back >= image.nbytes
    # The second render skips the strands' seven per-point float buffers (position,
    # tangent and colour of 3 floats; alpha, width, Ω and V of 1): 13 floats a point.
    assert first.uploaded - second.uploaded == 13 * 4 * scene.strands.num_points
    assert (second.draws, second.binds, second.read_back) == (first.draws, first.binds, first.read_back)
