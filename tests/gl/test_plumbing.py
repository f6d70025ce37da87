"""GL plumbing: context errors, shader errors, shared constants, the CLI's GL commands."""

import json

import numpy as np
import pytest

import hairjax as hj
from hairjax import _constants
from hairjax.cli import main
from hairjax.gl import GLError, GLUnavailable, _context, _programs

SMALL = """
[hair]
source = "furball"
strands = 80
points = 5
[camera]
width = 48
height = 40
[shadows]
maps = 4
resolution = 32
"""


def test_constants_come_from_one_definition():
    glsl = _programs.constants_glsl()
    for name in ("PIXEL_HALF_EXTENT", "SHADOW_FILTER_RADIUS", "SPECULAR_BASE_EPS", "SAFE_NORM_EPS"):
        value = getattr(_constants, name)
        assert f"{name} = {value!r};" in glsl
    model = _programs.shader_source("model.glsl")
    assert '#include "hairjax_constants"' in model
    # No shader spells a model constant as a literal instead of including it.
    for shader in ("camera.frag", "light_slice.frag", "ribbon.geom", "omega_maps.comp"):
        assert "0.5 * vin[0].width + 0.5" not in _programs.shader_source(shader)


def test_missing_egl_names_the_packages(monkeypatch):
    import moderngl

    def no_egl(**kwargs):
        raise RuntimeError("libEGL.so.1: cannot open shared object file")

    monkeypatch.setattr(moderngl, "create_context", no_egl)
    # The uncached function: the session's cached context stays as it is.
    with pytest.raises(GLUnavailable, match="libegl1 libgl1-mesa-dri"):
        _context.get_context.__wrapped__()


def test_the_context_asks_egl_for_the_version_it_needs(monkeypatch):
    """NVIDIA's EGL gives the 3.3 core context moderngl asks for by default (seen on an
    H200 with driver 580): the version needed must be asked for, not only checked."""
    import moderngl

    asked = {}

    def record(**kwargs):
        asked.update(kwargs)
        raise RuntimeError("stop here")

    monkeypatch.setattr(moderngl, "create_context", record)
    with pytest.raises(GLUnavailable, match="4.5"):
        _context.get_context.__wrapped__()
    assert asked.get("require", 0) >= _context.MIN_GL_VERSION


def test_cli_reports_missing_gl_and_jax_still_works(monkeypatch, tmp_path, capsys):
    import hairjax.gl

    def unavailable():
        raise GLUnavailable("no EGL here; apt-get install libegl1 libgl1-mesa-dri")

    scene = tmp_path / "s.toml"
    scene.write_text(SMALL)
    monkeypatch.setattr(hairjax.gl._renderer, "get_context", unavailable)
    assert main(["render", str(scene), "--backend", "gl", "-o", str(tmp_path / "g.exr")]) == 2
    assert "libegl1" in capsys.readouterr().err
    assert main(["render", str(scene), "-o", str(tmp_path / "j.exr")]) == 0


def test_shader_compile_errors_name_the_shader(gl, monkeypatch):
    original = _programs.shader_source
    monkeypatch.setattr(
        _programs,
        "shader_source",
        lambda name: original(name) + ("\nnot glsl;" if name == "camera.frag" else ""),
    )
    _programs.clear_cache()
    try:
        with pytest.raises(GLError, match=r"camera.*camera\.frag"):
            _programs.programs(gl)
    finally:
        monkeypatch.undo()
        _programs.clear_cache()


def test_render_gl_and_compare_from_the_cli(gl, tmp_path, capsys):
    scene = tmp_path / "s.toml"
    scene.write_text(SMALL)
    out = tmp_path / "gl.exr"
    assert main(["render", str(scene), "--backend", "gl", "-o", str(out), "--profile"]) == 0
    image = hj.read_image(out)
    assert image.shape == (40, 48, 4) and image[..., 3].max() > 0
    report = tmp_path / "cmp.json"
    assert main(["compare", str(scene), "--json", str(report), "--repeats", "1"]) == 0
    text = capsys.readouterr().out
    assert "RMSE" in text and "PSNR" in text
    data = json.loads(report.read_text())
    for key in ("max_abs", "rmse", "psnr_db", "share_over_1e-4", "tau_max_abs", "jax_s", "gl_s"):
        assert key in data
    assert data["rmse"] < 1e-3 and data["jax_s"] > 0 and data["gl_s"] > 0
    # The GL image written by render equals a direct render_gl (float32 EXR).
    from hairjax.gl import render_gl

    np.testing.assert_array_equal(image, render_gl(hj.load_scene(scene)).image)


def small_scene(tmp_path, shadows="opacity-maps"):
    path = tmp_path / "s.toml"
    options = {"opacity-maps": "maps = 4\nresolution = 32", "exact": "resolution = 32", "none": ""}
    path.write_text(SMALL.replace("maps = 4\nresolution = 32", f'{options[shadows]}\nmethod = "{shadows}"'))
    return hj.load_scene(path)


def test_no_shadow_passes_without_shadows(gl, tmp_path, monkeypatch):
    from hairjax.gl import _shadow_passes, render_gl

    def forbidden(*args, **kwargs):
        raise AssertionError("shadow passes ran for a scene without shadows")

    for method in ("opacity-maps", "exact"):
        monkeypatch.setitem(_shadow_passes._PASSES, method, forbidden)
    result = render_gl(small_scene(tmp_path, "none"))
    assert result.omega is None and "shadows" not in result.timings


def test_slice_clipping_draws_less_and_changes_nothing(gl, tmp_path, monkeypatch):
    """kim-2003 §4.2: drawing only the segments that meet each slice gives the same Ω."""
    from hairjax.gl import _buffers, render_gl

    drawn = []
    original = _buffers.Strands.index_buffer

    def counting(self, segment_ids):
        drawn.append(len(segment_ids))
        return original(self, segment_ids)

    monkeypatch.setattr(_buffers.Strands, "index_buffer", counting)
    scene = small_scene(tmp_path)
    clipped = render_gl(scene, clip_slices=True)
    n_clipped = drawn[0]
    drawn.clear()
    full = render_gl(scene, clip_slices=False)
    n_full = drawn[0] * scene.shadows.maps  # every segment, in every one of the N passes
    np.testing.assert_array_equal(clipped.omega, full.omega)
    np.testing.assert_array_equal(clipped.image, full.image)
    assert n_clipped < n_full / 2


def test_render_gl_takes_a_given_draw_order(gl, tmp_path):
    """`render_gl(..., order=…)`: the scene's own order gives the identical image; the
    order of the same scene sorted otherwise gives that scene's image."""
    from hairjax._geometry_stage._setup import visibility_order
    from hairjax.gl import render_gl

    scene = small_scene(tmp_path)
    plain = render_gl(scene).image
    np.testing.assert_array_equal(render_gl(scene, order=visibility_order(scene)[4]).image, plain)
    unsorted = scene.replace(ordering=hj.Ordering("none"))
    reused = render_gl(scene, order=visibility_order(unsorted)[4]).image
    np.testing.assert_array_equal(reused, render_gl(unsorted).image)
    assert np.abs(reused - plain).max() > 1e-3  # the order was used
