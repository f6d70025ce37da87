"""hairjax.fit with the strands' opacity (docs/fitting.md, "Fitting the strands' opacity")."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import central_difference, small_furball_scene

import hairjax as hj
from hairjax._fit import _opacity_fit

TRUE = hj.ShadingParams(kd=(0.3, 0.5, 0.2), ks=0.4, shininess=25.0, kappa=2.5, ambient=0.05)
INIT = hj.ShadingParams(kd=0.5, ks=0.2, shininess=10.0, kappa=1.0, ambient=0.05)
NAMES = ("kd", "ks", "shininess", "kappa", "alpha")
SPHERE = hj.Occluder(center=(0.0, 0.0, 0.0), radius=0.3, color=(0.8, 0.6, 0.5))


def terms_and_point(scene, params, alpha):
    model = _opacity_fit.opacity_fit_model(type(scene.shading))
    hw = scene.camera.width * scene.camera.height
    point = _opacity_fit.OpacityParams(params, jnp.asarray(alpha))
    data = model.prepare(scene, point, NAMES, np.zeros((hw, 3)), np.ones((hw, 1)))
    return model, data, point


@pytest.mark.parametrize("shadows", ["opacity-maps", "exact", "deep", "none", "sphere"])
def test_the_fit_image_at_alpha_is_the_render_at_alpha(shadows):
    """The fit recomputes the weights and scales Ω(1) by α (Ω linear in the strands'
    opacity); the renderer runs the geometry stage at α itself. Both, at an α other than
    the scene's, give one image (with an occluder: its Ω, transmittance and colour)."""
    scene = small_furball_scene(
        strands=80, size=24, shadows="opacity-maps" if shadows == "sphere" else shadows
    )
    if shadows == "sphere":
        scene = scene.replace(occluder=SPHERE)
    model, data, point = terms_and_point(scene, TRUE, 0.35)
    image = model.image(data, point)
    expected = hj.render(scene, TRUE, _opacity_fit.strand_alpha(scene, 0.35))[..., :3].reshape(-1, 3)
    # The same float64 sums in another order (per gain, then weighted): rounding only.
    np.testing.assert_allclose(image, expected, rtol=0, atol=1e-12)
    assert (
        np.max(np.abs(image - model.image(data, dataclasses.replace(point, alpha=jnp.asarray(0.6))))) > 1e-3
    )


def test_the_image_derivative_in_alpha_matches_finite_differences():
    scene = small_furball_scene(strands=80, size=24).replace(occluder=SPHERE)
    model, data, point = terms_and_point(scene, TRUE, 0.45)
    weights = jnp.asarray(np.random.default_rng(0).normal(size=(24 * 24, 3)))

    def f(a):
        return jnp.sum(weights * model.image(data, dataclasses.replace(point, alpha=jnp.asarray(a))))

    # Central differences at h = 1e-5 in float64: truncation O(h²) ≈ 1e-10 relative.
    np.testing.assert_allclose(jax.grad(f)(0.45), central_difference(f, 0.45, 1e-5), rtol=1e-7)


@pytest.mark.slow
def test_alpha_is_recovered_with_the_shading_parameters():
    scene = small_furball_scene(strands=120, size=32)  # strands' opacity 0.6: the start
    target = np.asarray(hj.render(scene, TRUE, _opacity_fit.strand_alpha(scene, 0.4)))
    r = hj.fit(scene, target, init=INIT, variables=NAMES, stop=hj.FitStop(max_steps=200))
    assert r.termination == "converged" and r.undetermined == ()
    # The noise-free recovery bound of docs/fitting.md: 1e-3 relative.
    assert abs(r.alpha - 0.4) < 1e-3 * 0.4 and r.initial_alpha == pytest.approx(0.6)
    for name in ("kd", "ks", "shininess", "kappa"):
        np.testing.assert_allclose(getattr(r.params, name), getattr(TRUE, name), rtol=1e-3)
    assert r.get("alpha") == r.alpha and r.get("alpha", initial=True) == r.initial_alpha
    assert np.isfinite(r.std_error["alpha"]) and r.to_json()["alpha"] == r.alpha
    # The fitted image carries the fitted α.
    np.testing.assert_allclose(hj.fitted_image(scene, r), target, atol=1e-3 * np.max(target))


def test_alpha_is_not_fitted_with_the_light():
    scene = small_furball_scene(strands=40, size=16)
    with pytest.raises(hj.FitError, match="alpha is not fitted together with the light"):
        hj.fit(scene, np.zeros((16, 16, 3)), variables=("kd", "alpha", "light_color"))
