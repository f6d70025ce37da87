"""Numerical stability of the GL renderer (the shared part and the other stages:
tests/stability_helpers.py): GL's depth test in a scene 10⁻⁴ units across, and
every guard in the shaders and in hairjax/gl.

Most GLSL guards are reached by the `gl` backend of another stage's cases (the generic
checks there compare GL with JAX float64); the table names where:

| case                            | test_…                                  | scene: own assertions          |
|---------------------------------|-----------------------------------------|--------------------------------|
| GL depth test at 1e-4           | gl_depth_test_keeps_its_resolution_…    | occluder, by hand              |

Found here: GL's depth test floored `far` at 2 units, so a scene 1e-4 units across
resolved depth to 4e-4 (hair just in front of the occluder vanished): fixed in
gl/_renderer.py (now gl/_camera_pass.py's camera_depth_far).

| guard (file: function)                          | test_guard_… (or test_… in full)                      |
|-------------------------------------------------|-------------------------------------------------------|
| model.glsl: project max(z, near)                | geometry: test_camera_inside_the_hair[gl]             |
| model.glsl: fragment_depth z0 == z1             | geometry: test_all_points_at_one_depth[gl]            |
| model.glsl: safe_norm                           | shading: test_tangents_parallel_to_light_and_view[gl] |
| model.glsl: specular_power                      | shading: test_shininess_extremes[mixed-0.5-gl]        |
| model.glsl: kajiya_kay_gap, b ≤ 0               | glsl_kajiya_kay_gap_and_log1p                         |
| model.glsl: log1p_accurate, x ∉ (−½, 1)         | glsl_kajiya_kay_gap_and_log1p                         |
| model.glsl: safe_normalize, in marschner_lobes  | glsl_marschner_lobes (L or V ∥ T)                     |
| model.glsl: safe_normalize, in strand.vert      | geometry: test_point_light_at_a_strand_point[gl]      |
| model.glsl: fresnel_dielectric clamp            | glsl_marschner_lobes                                  |
| model.glsl: safe_sqrt (cos θ_d = 0)             | glsl_marschner_lobes                                  |
| model.glsl: marschner_lobes series (f·T → 1)    | glsl_marschner_lobes                                  |
| model.glsl: grid_cell clamp (sin θ beyond ±1)   | test_marschner: glsl_dual_terms_match_jax_at_points   |
| model.glsl: slice_of clamp                      | geometry: test_all_points_at_one_depth[gl] (maps)     |
| ribbon.geom: zero-length segments               | geometry: test_zero_length_segments_…_points[gl]      |
| omega_maps.comp: outside the map, f clamp       | geometry: test_point_light_at_the_hairs_centre[gl]    |
| omega_exact.comp: texels outside the map        | geometry: test_point_light_at_a_strand_point[gl]      |
| occluder_sphere.frag: t > 0                     | point_light_on_the_occluder (eye outside)             |
| occluder_color.frag: light on the surface       | point_light_on_the_occluder                           |
| occluder_mesh.frag: zero interpolated normal    | unreachable in practice: only at a vertex             |
|                                                 | whose faces' normals cancel exactly                   |
| occluder_visibility.comp: off the map           | not reached by a test (JAX's is: test_occluder::…     |
|                                                 | degenerate_triangles_…)                               |
| hairjax/gl: no drawable triangle                | test_occluder::…a_mesh_behind_the_eye                 |
| hairjax/gl: empty buffers, ortho near           | geometry: test_guard_exact_shadows_without_fragments  |
| gl/_camera_pass: camera_depth_far (fixed)       | test_gl_depth_test_keeps_its_resolution_…             |

"geometry:" is tests/geometry/test_stability.py, "shading:" tests/shading/test_stability.py,
"test_occluder::" tests/geometry/test_occluder.py, "test_marschner:" tests/gl/test_marschner.py.
"""

from __future__ import annotations

import numpy as np
import pytest
from helpers import unexplained_pixels
from stability_helpers import (
    glsl_highlight,
    glsl_marschner_lobes,
    jax_marschner_lobes,
    run_glsl,
    unit_roundoff,
)

import hairjax as hj
from hairjax._errors import EmptyViewWarning

# --- the cases -----------------------------------------------------------------------------


def test_gl_depth_test_keeps_its_resolution_at_1e_minus_4(gl):
    """Hair just in front of / just behind the occluder (relative depth gaps 3e-5 … 3e-4,
    beyond tests/gl/test_renderer.py's 1e-5 band for "at the sphere's depth") in a scene
    10⁻⁴ units across: GL's depth test must classify each like JAX. The depth buffer stores
    depth/far in 2⁻²⁴ steps; with `far` floored at 2 units the step was 4e-4 of these depths
    (bug, fixed in _camera_pass)."""
    from hairjax._geometry._projection import camera_view
    from hairjax.gl import render_gl

    s = 1e-4
    cam = hj.Camera(eye=(0.0, 0.0, 4 * s), target=(0.0, 0.0, 0.0), fov=40.0, width=33, height=33)
    origin, direction = camera_view(cam).pixel_rays()
    rows = np.arange(6, 28, 2)  # rows whose centre ray meets the sphere (|row − 16| < 11.7)
    gaps = np.geomspace(3e-5, 3e-4, len(rows)) * np.where(np.arange(len(rows)) % 2, -1, 1)
    strands, lambert = [], []
    for row, gap in zip(rows, gaps):
        o, d = origin[row * 33 + 16], direction[row * 33 + 16]
        # The ray's first hit on the sphere of radius s at the origin, by hand.
        b = o @ d
        t = -b - np.sqrt(b * b - (o @ o - s * s))
        lambert.append((o + t * d)[2] / s)  # N·L with L = +z
        _, y, z = o + t * (1 - gap) * d  # a horizontal hair at the hit's depth × (1 − gap)
        strands.append([[-0.3 * s, y, z], [0.3 * s, y, z]])
    scene = hj.Scene(
        hj.Strands.from_list(strands, alpha=1.0),
        camera=cam,
        light=hj.Light(direction=(0.0, 0.0, -1.0)),
        occluder=hj.Occluder(center=(0.0, 0.0, 0.0), radius=s, color=(0.2, 0.2, 0.2)),
        shadows=hj.Shadows("none"),
        shading=hj.KajiyaKay(hj.ShadingParams(kd=0.0, ks=0.0, ambient=1.0)),
    )
    jax_image = np.asarray(hj.render(scene))
    gl_image = render_gl(scene).image
    # By hand: hair in front (gap > 0) shows white (it runs through the pixel centre:
    # coverage 1 up to the projection's rounding, ~1e-13), behind it the sphere's
    # 0.2·(ambient + N·L), ambient 1 (§13). GL: the same to float32 rounding (a few ulps).
    expected = np.where(gaps > 0, 1.0, 0.2 * (1.0 + np.asarray(lambert)))
    np.testing.assert_allclose(jax_image[rows, 16, 0], expected, rtol=0, atol=1e-12)
    np.testing.assert_allclose(gl_image[rows, 16, 0], expected, rtol=0, atol=1e-6)
    bad, _ = unexplained_pixels(scene, gl_image, jax_image)
    assert bad.size == 0


# --- the guards ----------------------------------------------------------------------------
# One test per guard (the table in the module docstring): inputs that make it fire, and the
# guarded result checked against the model's value.


def test_guard_glsl_kajiya_kay_gap_and_log1p(gl):
    """model.glsl: kajiya_kay_gap's b ≤ 0 branch on the cases of
    test_guard_kajiya_kay_gap_on_the_far_side (tests/shading/test_stability.py: b = −1,
    where s²/(1 + b) is 0/0; 0; −0.75): gap = 1 − b by hand, and shade_point's Ks·b^p
    exactly 0 (specular_power's cut). And log1p_accurate's branches: the atanh series for
    −½ < x < 1 (down to x below ulp(1)/2, where 1 + x = 1) and log(1 + x) outside, each
    within 16u of float64 log1p (GLSL allows division 2.5 ulps and log 3 ulps, 2⁻²¹
    absolute on [0.5, 2]; llvmpipe: ≤ 3u), where plain log(1 + x) is off by 10⁵ u and more
    near 0 (asserted: the reason for the function)."""
    x, y = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
    w = np.array([0.6614378, 0.75, 0.0])
    for model, rows, b in (
        ("kajiya-kay", [(x, x, -x), (x, y, x), (y, w, -y)], [-1.0, 0.0, -0.75]),
        ("kajiya-kay-mirror", [(x, x, x), (y, w, y)], [-1.0, -0.75]),
    ):
        t, light, eye = (np.array(c, np.float32) for c in zip(*rows))
        out = glsl_highlight(gl, t, light, eye, model, 1e4)
        np.testing.assert_array_equal(out[:, 1], 1.0 - np.float32(b))
        np.testing.assert_array_equal(out[:, 0], 0.0)
        for p in (0.5, 1.0):
            np.testing.assert_array_equal(glsl_highlight(gl, t, light, eye, model, p)[:, 0], 0.0)
    xs = np.concatenate(
        [-np.geomspace(1e-9, 0.49, 60), np.geomspace(1e-9, 0.99, 60), [-0.5, -0.75, -0.999, 1.0, 3.0, 1e3]]
    ).astype(np.float32)
    body = "    outp[2u * i] = log1p_accurate(inp[i]);\n    outp[2u * i + 1u] = log(1.0 + inp[i]);"
    out = run_glsl(gl, body, xs[:, None], 2)
    exact = np.log1p(xs.astype(np.float64))
    rel = np.abs(out.astype(np.float64) - exact[:, None]) / np.abs(exact[:, None])
    u = unit_roundoff(np.float32)
    assert rel[:, 0].max() <= 16 * u, xs[np.argmax(rel[:, 0])]
    assert rel[:, 1].max() >= 1e5 * u  # plain log(1 + x): 1 + x rounds away x's low bits


# (T, L, V) rows where marschner_lobes' guards fire, float32: L and V along the fibre and
# opposite (cos θ_d = 0: safe_sqrt at 0, both projections 0 for safe_normalize, Fresnel 1,
# and with σ_a = 0 the TRT series' 1 − f·T = 0); L along the fibre; V along it; back-lit
# exactly (φ = π, cos(φ/2) = 0); a unit vector an ulp long (Fresnel's clamp at cos > 1).
_X, _Y, _Z = np.eye(3)
_LONG = np.float32(1.0) + np.float32(2.0**-23)
MARSCHNER_GUARD_ROWS = [
    (_X, _X, -_X),
    (_X, _X, _Y),
    (_X, _Y, _X),
    (_X, _Y, -_Y),
    (_X, _Z * _LONG, _Z * _LONG),
]


@pytest.mark.parametrize("roughness", [0.02, 1.0])
@pytest.mark.parametrize("melanin", [0.0, 8.0])
def test_guard_glsl_marschner_lobes(gl, melanin, roughness):
    """model.glsl's marschner_lobes where its guards fire (MARSCHNER_GUARD_ROWS), σ_a = 0
    (melanin 0) and large (8), the roughness extremes: finite, and equal to the JAX model
    (float64, on the same float32 inputs; its guards are the same, each tested in
    tests/shading/) within 2e-5 of each lobe's largest value over the rows plus 1e-6
    (float32 rounding of values ≤ ~50, tests/gl/test_marschner.py measures ≤ 4e-6
    relative); the first row, where no light passes, exactly 0 in GL."""
    params = hj.MarschnerParams(
        eumelanin=melanin, pheomelanin=0.0, longitudinal_roughness=roughness, tilt=2.0
    )
    t, light, eye = (np.array(c, np.float32) for c in zip(*MARSCHNER_GUARD_ROWS))
    got = glsl_marschner_lobes(gl, t, light, eye, params)
    want = jax_marschner_lobes(t, light, eye, params)
    assert np.all(np.isfinite(got)) and np.all(np.isfinite(want))
    scale = np.abs(want).max(axis=0)
    assert np.all(np.abs(got - want) <= 2e-5 * scale + 1e-6), (got, want)
    np.testing.assert_array_equal(got[0], 0.0)


def test_guard_point_light_on_the_occluder(gl):
    """A point light exactly on the sphere at the centre pixel's hit point: JAX's _unit
    gives L = 0 there (Lambert 0), occluder_color.frag's guarded normalisation too: both
    must show the ambient part k·ambient only, finite."""
    from hairjax.gl import render_gl

    hair = hj.Strands.from_list([[[-0.5, 1.5, 0.5], [0.5, 1.5, 0.5]]], alpha=0.5)
    scene = hj.Scene(
        hair,
        camera=hj.Camera(eye=(0.0, 0.0, 4.0), width=9, height=9),
        light=hj.Light(kind="point", position=(0.0, 0.0, 1.0)),
        occluder=hj.Occluder(center=(0.0, 0.0, 0.0), radius=1.0, color=(1.0, 1.0, 1.0)),
        shadows=hj.Shadows("none"),
    )
    # The hair lies above the view (y = 1.5 at depth 3.5: tan 23° > tan 20°); the test is
    # about the occluder, and the set-up says that the hair covers no pixel. The render's
    # own set-up (its cutoff), which the render below then reuses.
    with pytest.warns(EmptyViewWarning):
        setup = hj.experimental.prepare(scene, cutoff=hj.experimental.render_cutoff())
        assert np.array_equal(setup.view.pixel_rays()[1][4 * 9 + 4], [0.0, 0.0, -1.0])
    jax_image, gl_image = np.asarray(hj.render(scene)), render_gl(scene).image
    assert np.all(np.isfinite(gl_image))
    amb = np.asarray(scene.params.ambient, np.float64) * np.ones(3)  # k = 1
    np.testing.assert_array_equal(jax_image[4, 4], [*amb, 1.0])
    np.testing.assert_allclose(gl_image[4, 4], [*amb, 1.0], rtol=1e-7)
    np.testing.assert_allclose(gl_image, jax_image, rtol=0, atol=1e-6)
