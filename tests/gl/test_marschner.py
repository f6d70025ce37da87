"""The GL renderer's `marschner` branch (docs/model.md §11, §19) against the JAX model,
which is independent code (hairjax/_shading/_marschner_lobes.py; model.glsl's
`marschner_lobes` is its GLSL transcription).

- Images: a small fur ball front- and back-lit, melanin 0 and 8, roughness 0.02 and 1,
  the scales tilted by 3°: GL with JAX's Ω equals JAX but in the band that boundaries
  within rounding explain (hairjax/_disagreement, tolerances there).
- A wrong shader (the tilt's sign flipped, two lobes swapped, the melanin's absorption
  dropped) leaves pixels the band does not explain: the check can fail.
- Points: GLSL's lobes at directions in every octant, float32 against JAX float64.
"""

from __future__ import annotations

import numpy as np
import pytest
from helpers import MAX_BAND, PIXEL_TOL, render_gl_with_edited_shader, small_furball_scene, unexplained_pixels
from stability_helpers import glsl_dual_terms, glsl_marschner_lobes, jax_dual_terms, jax_marschner_lobes

import hairjax as hj

FRONT = (-0.5, -0.7, -0.4)  # from above and in front of the camera's side
BACK = (0.0, 0.0, 1.0)  # toward the camera (at z = 3.5): the hair is back-lit


def scene(light, scattering="none", **params) -> hj.Scene:
    """200 strands at 64², shaded by `marschner` with the scales tilted by 3°."""
    base = small_furball_scene(strands=200, size=64)
    values = dict(pheomelanin=0.0, tilt=3.0, kappa=0.8, ambient=0.05) | params
    model = hj.Marschner(hj.MarschnerParams(**values), multiple_scattering=scattering)
    return base.replace(shading=model, light=hj.Light(direction=light))


@pytest.fixture(scope="module")
def geometries():
    """The geometry stage per light and `multiple_scattering` (the geometry holds the model
    object), computed once (float64); the parameters do not enter it."""
    cache: dict = {}

    def get(light, scattering="none"):
        if (light, scattering) not in cache:
            cache[light, scattering] = hj.geometry_stage(scene(light, scattering))
        return cache[light, scattering]

    return get


def images(geometries, light, scattering="none", **params):
    """(scene, JAX image, GL image with JAX's Ω)."""
    from hairjax.gl import render_gl

    s = scene(light, scattering, **params)
    geometry = geometries(light, scattering)
    jax_image = np.asarray(hj.shading_stage(geometry, s.params))
    return s, jax_image, render_gl(s, omega=np.asarray(geometry.omega)).image


@pytest.mark.parametrize("light", [FRONT, BACK], ids=["front", "back"])
@pytest.mark.parametrize("melanin", [0.0, 8.0])
@pytest.mark.parametrize("roughness", [0.02, 1.0])
def test_gl_matches_jax(gl, geometries, light, melanin, roughness):
    s, jax_image, gl_image = images(
        geometries, light, eumelanin=melanin, longitudinal_roughness=roughness, ambient=0.0
    )
    assert np.all(np.isfinite(gl_image))
    bad, band = unexplained_pixels(s, gl_image, jax_image)
    assert bad.size == 0, f"{bad.size} pixels differ with no boundary nearby"
    assert band.mean() <= MAX_BAND
    # The lobes are in the image (no ambient here, a black backdrop): > 5 tolerances
    # somewhere even for black rough hair back-lit, the darkest case (it peaks at 9.7e-4).
    assert jax_image[..., :3].max() > 5 * PIXEL_TOL


# Each edit changes one term of model.glsl's marschner_lobes / dual_terms / shade_marschner.
WRONG = {
    "tilt sign (R)": ("tilted(a.sin_v, a.cos_v, tilts.x)", "tilted(a.sin_v, a.cos_v, -tilts.x)"),
    "tilt sign (TT)": ("tilted(a.sin_v, a.cos_v, tilts.y)", "tilted(a.sin_v, a.cos_v, -tilts.y)"),
    "TT and TRT weights swapped": (
        "vec3[3](m.weight_r, m.weight_tt, m.weight_trt)",
        "vec3[3](m.weight_r, m.weight_trt, m.weight_tt)",
    ),
    "TT and TRT Gaussians swapped": ("tt = pi * m_tt", "tt = pi * m_trt"),
    "R and TRT widths swapped": ("lobe_gaussian(vec3(m.widths.x),", "lobe_gaussian(vec3(m.widths.z),"),
    "no absorption in TT": (
        "fibre_transmittance(sigma_a, h_tt, a, cos_t)",
        "fibre_transmittance(vec3(0.0), h_tt, a, cos_t)",
    ),
    "dual: scattered light shadowed by τ": (
        "visibility * light_rgb * scattered_sum",
        "tau * light_rgb * scattered_sum",
    ),
    "dual: no spread with the fibres in front": (
        "vec3 var_s = count * dual_at(",
        "vec3 var_s = 0.0 * dual_at(",
    ),
    "dual: Δ_b and σ_b rows swapped": ("const int DUAL_SHIFT_BACK = 3;", "const int DUAL_SHIFT_BACK = 4;"),
    "dual: N^G at the next cos φ node": (
        "dual_at(tables, DUAL_N_G + 3 * k + p",
        "dual_at(tables, DUAL_N_G + 3 * (k + 1) + p",
    ),
}


@pytest.mark.parametrize("edit", WRONG, ids=list(WRONG))
def test_a_wrong_marschner_shader_fails_the_check(gl, geometries, edit):
    """Roughness 0.1 (widths 0.04 … 0.16 in sin θ) with the tilt 3° (shifts 0.05 … 0.2),
    lobe weights 0.8, 1, 0.5: every edit moves the image by far more than the band;
    back-lit, TT and TRT both show. Dual scattering's edits with it on."""
    old, new = WRONG[edit]
    weights = dict(weight_r=0.8, weight_tt=1.0, weight_trt=0.5)
    scattering = "dual" if "dual" in edit else "none"
    s, jax_image, gl_image = images(
        geometries, BACK, scattering, eumelanin=1.0, longitudinal_roughness=0.1, **weights
    )
    assert unexplained_pixels(s, gl_image, jax_image)[0].size == 0
    geometry = geometries(BACK, scattering)
    wrong = render_gl_with_edited_shader(s, np.asarray(geometry.omega), old, new)
    bad, _ = unexplained_pixels(s, wrong, jax_image)
    assert bad.size > 20, f"{edit}: only {bad.size} pixels caught"


@pytest.mark.parametrize("light", [FRONT, BACK], ids=["front", "back"])
@pytest.mark.parametrize(("melanin", "roughness"), [(0.0, 0.02), (8.0, 1.0), (1.3, 0.3)])
def test_dual_scattering_gl_matches_jax(gl, geometries, light, melanin, roughness):
    """multiple_scattering = "dual" (docs/model.md §19): GL (the tables computed by the JAX
    code, interpolated in GLSL) equals JAX but in the band, at the extremes and a brown;
    and the dual terms are in the image: it differs from single scattering's by > 10
    tolerances but for black hair (measured 1.1e-4 for black rough hair: black fibres pass
    little light on, and little is scattered between them)."""
    values = dict(eumelanin=melanin, longitudinal_roughness=roughness, ambient=0.0)
    s, jax_image, gl_image = images(geometries, light, "dual", **values)
    assert np.all(np.isfinite(gl_image))
    bad, band = unexplained_pixels(s, gl_image, jax_image)
    assert bad.size == 0, f"{bad.size} pixels differ with no boundary nearby"
    assert band.mean() <= MAX_BAND
    if melanin < 8.0:  # black fibres pass little light on: dual adds ~1e-4 to rough black hair
        _, single, _ = images(geometries, light, "none", **values)
        assert np.abs(jax_image - single).max() > 10 * PIXEL_TOL


def unit_rows(n: int, seed: int) -> np.ndarray:
    v = np.random.default_rng(seed).normal(size=(n, 3))
    return (v / np.linalg.norm(v, axis=1, keepdims=True)).astype(np.float32)


@pytest.mark.parametrize("roughness", [0.02, 0.3, 1.0])
@pytest.mark.parametrize("melanin", [0.0, 8.0])
def test_glsl_lobes_match_jax_at_points(gl, roughness, melanin):
    """2000 random unit (T, L, V) in float32, GLSL against JAX float64 on the same float32
    inputs, the scales tilted by 3°. Tolerance: 2e-5 of each lobe's largest value over the
    rows (measured ≤ 4e-6 on these cases, llvmpipe: float32's 6e-8 times the Gaussian's
    (x/std)² and the exponentials' arguments)."""

    def params_at(tilt):
        return hj.MarschnerParams(
            eumelanin=melanin, pheomelanin=0.3, longitudinal_roughness=roughness, tilt=tilt
        )

    params = params_at(3.0)
    t, light, eye = unit_rows(2000, 1), unit_rows(2000, 2), unit_rows(2000, 3)
    got = glsl_marschner_lobes(gl, t, light, eye, params)
    want = jax_marschner_lobes(t, light, eye, params)
    scale = np.abs(want).max(axis=0)
    assert np.all(np.isfinite(got))
    assert np.all(np.abs(got - want) <= 2e-5 * scale), np.abs(got - want).max(axis=0) / scale
    # Not vacuous: the tilt flipped moves R by > 10 tolerances, even at roughness 1.
    flipped = jax_marschner_lobes(t, light, eye, params_at(-3.0))
    assert np.abs(flipped - want)[:, 0].max() > 10 * 2e-5 * scale[0]


@pytest.mark.parametrize(("melanin", "roughness"), [(0.0, 0.02), (8.0, 1.0), (1.3, 0.3)])
def test_glsl_dual_terms_match_jax_at_points(gl, melanin, roughness):
    """model.glsl's dual_terms (tables from `gl_table`, interpolated in GLSL) against JAX's
    (float64) at 2000 random (T, L, V) with n ∈ [0, 20] fibres in front (a tenth up to 2000,
    where e^{n·ā_f} overflows float32: NaN in GL before its Ψ was written without it), plus L along the
    fibre both ways with the light's sin θ an ulp beyond ±1 (grid_cell's clamp). Tolerance:
    2e-5 of each term's largest value over the rows plus 1e-7 of the largest overall
    (measured ≤ 1.3e-5 of the term's peak where that is above 1e-7 of the largest; the
    tables are rounded to float32, and the Gaussians err as in
    test_glsl_lobes_match_jax_at_points); n halved moves the terms by > 0.7 of their peak."""
    params = hj.MarschnerParams(
        eumelanin=melanin, pheomelanin=0.3, longitudinal_roughness=roughness, tilt=3.0
    )
    long = np.float32(1.0) + np.float32(2.0**-23)
    x, y = np.array([[1.0, 0.0, 0.0]], np.float32), np.array([[0.0, 1.0, 0.0]], np.float32)
    t = np.concatenate([unit_rows(2000, 1), x, x])
    light = np.concatenate([unit_rows(2000, 2), x * long, -x * long])
    eye = np.concatenate([unit_rows(2000, 3), y, y])
    counts = np.random.default_rng(4).uniform(0.0, 20.0, 2000)
    # Deep in the hair: n ≤ 2000, n·ā_f beyond float32's exp range (88) and float64's (709).
    counts[::10] *= 100.0
    count = np.concatenate([counts, [3.0, 3.0]]).astype(np.float32)
    got = glsl_dual_terms(gl, t, light, eye, count, params)
    want = jax_dual_terms(t, light, eye, count, params)
    assert np.all(np.isfinite(got)) and np.all(np.isfinite(want))
    scale = np.abs(want).max(axis=0)
    bound = 2e-5 * scale + 1e-7 * scale.max()
    assert np.all(np.abs(got - want) <= bound), (np.abs(got - want) / scale).max(axis=0)


def test_gl_refuses_the_far_field_azimuth(gl):
    """`azimuthal = "chiang"` has no shader: one SceneError naming the key, not Karis's
    image under the far field's name."""
    from hairjax.gl import render_gl

    far = scene(FRONT).replace(shading=hj.Marschner(azimuthal="chiang"))
    assert far.shading.gl_unsupported() is not None
    with pytest.raises(hj.SceneError, match="azimuthal"):
        render_gl(far)
