"""The two ways GL expands segments into ribbons (hairjax/gl/_ribbons.py, docs/model.md §5,
§11): vertex pulling and the geometry shader make the same fragments with the same values,
so every pass gives the same image and Ω, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import gl_with_edited_shader, small_furball_scene

import hairjax as hj
from hairjax.gl._work import counted_gl_work


def _scenes(method: str) -> list[hj.Scene]:
    """A fur ball under `method`'s shadows; ribbons 2.5 pixels wide; of world width from a
    point light, with an occluder; and one with zero-length segments (repeated points)."""
    scene = small_furball_scene(strands=60, size=40, shadows=method, maps=8, resolution=32)
    points = scene.strands.points.copy()
    points[1::6] = points[0::6]  # each strand's first segment has length 0
    return [
        scene,
        scene.replace(strands=scene.strands.replace(width=2.5)),
        scene.replace(
            strands=scene.strands.replace(width=0.06, width_units="world"),
            light=hj.Light(kind="point", position=(2.0, 2.5, 1.5)),
            occluder=hj.Occluder(center=(0.0, 0.0, 0.0), radius=0.3),
        ),
        scene.replace(strands=scene.strands.replace(points=points)),
    ]


@pytest.mark.parametrize("method", ["opacity-maps", "deep", "exact", "none"])
def test_both_expansions_give_the_same_image_and_omega(gl, method):
    from hairjax.gl import render_gl

    for scene in _scenes(method):
        pulled = render_gl(scene, ribbons="vertex-pulling")
        shaded = render_gl(scene, ribbons="geometry-shader")
        assert np.abs(pulled.image[..., 3]).max() > 0.5  # the hair is drawn
        np.testing.assert_array_equal(pulled.image, shaded.image)
        if method != "none":
            assert np.abs(pulled.omega).max() > 0.1
            np.testing.assert_array_equal(pulled.omega, shaded.omega)


def test_the_pulled_ribbons_read_their_segments(gl):
    """A draw that starts one segment late (`first_segment` shifted) draws other ribbons:
    the check above would see a wrong index into the segments' ends."""
    from hairjax.gl import render_gl

    scene = _scenes("none")[0]
    old = "int segment = first_segment + gl_VertexID / 6;"
    shifted = old.replace("/ 6;", "/ 6 + 1;")
    wrong = gl_with_edited_shader(scene, "ribbon_pulled.vert", old, shifted, ribbons="vertex-pulling").image
    assert np.abs(wrong - render_gl(scene, ribbons="geometry-shader").image).max() > 1e-2


def test_vertex_pulling_draws_without_a_geometry_shader_and_shades_each_point_once(gl):
    """The camera pass by vertex pulling: one transform-feedback draw of the points and
    one of the quads, where the geometry shader's takes one draw of lines."""
    from hairjax.gl import render_gl

    scene = _scenes("none")[0]
    counts = {}
    for expansion in ("vertex-pulling", "geometry-shader"):
        render_gl(scene, ribbons=expansion)  # resident strands uploaded, programs built
        with counted_gl_work() as work:
            render_gl(scene, ribbons=expansion)
        counts[expansion] = work.draws
    assert counts == {"vertex-pulling": 2, "geometry-shader": 1}


def test_an_unknown_expansion_is_refused():
    from hairjax.gl import render_gl

    with pytest.raises(ValueError, match="ribbons must be one of geometry-shader, vertex-pulling"):
        render_gl(_scenes("none")[0], ribbons="quads")
