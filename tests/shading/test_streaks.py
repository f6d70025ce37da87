"""The streak texture (docs/model.md §16): the exact mean against numerical integration,
its limits, how it enters the image, the scene file, and GL against JAX."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import PIXEL_TOL, small_furball_scene, unexplained_pixels

import hairjax as hj
from hairjax._errors import SceneError
from hairjax._shading import point_colors
from hairjax._shading._streaks import Streaks, streak_factor, streak_prefix, streak_texture


def mean_by_quadrature(texture, u, width, samples=200001):
    """The periodic linear interpolant (texel k at (k + ½)/m) averaged by the trapezoid rule."""
    m = len(texture)
    x = np.linspace(u, u + width, samples)
    y = np.mod(x * m - 0.5, m)
    g = np.interp(y, np.arange(m + 1), np.append(texture, texture[0]))
    return np.trapezoid(g, x) / width


@pytest.mark.parametrize("u, width", [(0.0, 0.37), (0.01, 0.05), (0.5, 1.0), (0.93, 0.3), (0.999, 0.002)])
def test_factor_is_the_mean_over_the_span(u, width):
    texture = streak_texture(Streaks(texels=7, contrast=0.8, seed=3))
    f = streak_factor(jnp.asarray(texture), jnp.asarray(streak_prefix(texture)), jnp.asarray(u), width)
    # Trapezoid rule on a piecewise-linear integrand with 2e5 panels: error ≤ a kink's
    # share, |ΔN|·(m·h)²/8 per kink, < 1e-10 here.
    assert float(f) == pytest.approx(mean_by_quadrature(texture, u, width), abs=1e-9)


def test_narrow_span_is_the_interpolated_texture_and_no_contrast_is_one():
    texture = streak_texture(Streaks(texels=5, contrast=0.5, seed=0))
    prefix = streak_prefix(texture)
    f = streak_factor(jnp.asarray(texture), jnp.asarray(prefix), jnp.asarray(0.37), 1e-7)
    # g(0.37) by hand: y = 0.37·5 − ½ = 1.35, between texels 1 and 2.
    assert float(f) == pytest.approx(0.65 * texture[1] + 0.35 * texture[2], abs=1e-6)
    flat = streak_texture(Streaks(texels=5, contrast=0.0))
    np.testing.assert_array_equal(flat, 1.0)
    f = jax.vmap(streak_factor, in_axes=(None, None, 0, None))(
        jnp.asarray(flat), jnp.asarray(streak_prefix(flat)), jnp.linspace(0, 0.999, 50), 0.2
    )
    np.testing.assert_allclose(f, 1.0, rtol=1e-13)


def test_streaks_scale_each_hairs_whole_colour():
    streaks = Streaks(texels=16, width=0.1, contrast=0.8, seed=1)
    scene = small_furball_scene(strands=30, size=32, streaks=streaks)
    plain = scene.replace(streaks=None)
    geom, geom_plain = hj.geometry_stage(scene), hj.geometry_stage(plain)
    assert geom_plain.streak is None  # a scene without streaks computes none
    factor = np.asarray(geom.streak)
    strand = scene.strands.strand_of_point
    for s in range(scene.strands.num_strands):  # one value per hair: streaks run along it
        assert np.ptp(factor[strand == s]) == 0
    assert np.unique(factor).size == scene.strands.num_strands
    assert 0.2 <= factor.min() and factor.max() <= 1.0  # means of values in [1 − contrast, 1]
    colors = jax.jit(point_colors)
    np.testing.assert_allclose(
        colors(geom, scene.params), np.asarray(colors(geom_plain, scene.params)) * factor[:, None], rtol=1e-14
    )
    # Zero contrast renders the plain image.
    flat = scene.replace(streaks=Streaks(contrast=0.0))
    np.testing.assert_allclose(hj.render(flat), hj.render(plain), rtol=1e-12, atol=1e-14)


def test_scene_file_streaks_table(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text('[hair]\nsource = "furball"\nstrands = 3\n[streaks]\ntexels = 32\nwidth = 0.2\n')
    scene = hj.load_scene(path)
    assert scene.streaks == Streaks(texels=32, width=0.2)
    path.write_text('[hair]\nsource = "furball"\nstrands = 3\n')
    assert hj.load_scene(path).streaks is None
    for text, message in [
        ("width = 0", r"streaks\.width must be in \(0, 1\], got 0"),
        ("contrast = 2", r"streaks\.contrast must be in \[0, 1\], got 2"),
        ("texels = 1.5", r"streaks\.texels must be an integer, got 1\.5"),
    ]:
        path.write_text(f'[hair]\nsource = "furball"\nstrands = 3\n[streaks]\n{text}\n')
        with pytest.raises(SceneError, match=f"^{path}: {message}"):
            hj.load_scene(path)


def test_gl_streaks_match_jax(gl):
    """GL evaluates the same mean in float32 from the texture (N, P): H(y) is ≤ m·(1 + Δ) in
    size, so its rounding errs the factor by ~m·6e-8/(Δ·m) = 6e-8/Δ ≈ 6e-7 here, far below
    PIXEL_TOL; pixels differ by more only in the camera band (hairjax/_disagreement)."""
    from hairjax.gl import render_gl

    scene = small_furball_scene(
        strands=60, size=48, streaks=Streaks(texels=16, width=0.1, contrast=0.8, seed=1)
    )
    geom = hj.geometry_stage(scene)
    jax_image = np.asarray(hj.shading_stage(geom, scene.params))
    gl_image = render_gl(scene, omega=np.asarray(geom.omega)).image
    bad, _ = unexplained_pixels(scene, gl_image, jax_image)
    assert bad.size == 0, f"{bad.size} pixels differ by > {PIXEL_TOL}"
    plain = render_gl(scene.replace(streaks=None), omega=np.asarray(geom.omega)).image
    assert np.abs(plain - gl_image).max() > 100 * PIXEL_TOL  # GL does apply the streaks


def test_fit_terms_carry_the_streaks():
    """The fit's own image (its gain images, hairjax/_fit/_shading_fit.py) equals the
    renderer's for a scene with streaks (the fit leaves out fragments behind T < 1e-5, so to 1e-5 × the
    brightest colour, as tests/fit/test_fit.py states)."""
    from helpers import fit_image, fit_terms

    scene = small_furball_scene(strands=60, size=32, streaks=Streaks(contrast=0.8, seed=2))
    p = scene.params
    exact = np.asarray(hj.render(scene))[..., :3].reshape(-1, 3)
    terms = fit_terms(scene, p, ("kd", "ks", "shininess", "kappa"), exact.reshape(32, 32, 3))
    image = np.asarray(fit_image(terms, p.kd, p.ks, p.shininess, p.kappa, p.ambient))
    assert np.abs(image - exact).max() <= 1e-5 * exact.max()
    plain = np.asarray(hj.render(scene.replace(streaks=None)))[..., :3].reshape(-1, 3)
    assert np.abs(plain - exact).max() > 0.01  # the streaks do change this image
