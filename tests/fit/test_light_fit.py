"""hairjax.fit with the light (docs/fitting.md, "Fitting the light"): its image and
derivatives, a recovery, and what is refused."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import small_furball_scene

import hairjax as hj
from hairjax._constants import FIT_TRANSMITTANCE_CUTOFF
from hairjax._fit._light_fit import lit_fit_model, start_light
from hairjax._fit._lit import PLANE, LitParams

TRUE = hj.ShadingParams(kd=(0.3, 0.5, 0.2), ks=0.4, shininess=25.0, kappa=2.5, ambient=0.05)
# 17° from small_furball_scene's light (-0.5, -0.7, -0.4), and not white.
TRUE_LIGHT = hj.Light(direction=(-0.3, -0.8, -0.6), color=(1.0, 0.8, 0.6))


def unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


def test_plane_transform_is_a_unit_vector_about_its_reference():
    r = jnp.asarray([0.0, -1.0, 0.0])  # straight down: a pole of any angle parametrisation
    np.testing.assert_allclose(np.asarray(PLANE.forward(jnp.zeros(2), r)), r, atol=1e-15)
    for z in ([0.3, -0.2], [40.0, 25.0]):
        x = PLANE.forward(jnp.asarray(z), r)
        np.testing.assert_allclose(float(jnp.linalg.norm(x)), 1.0, rtol=1e-15)
        np.testing.assert_allclose(np.asarray(PLANE.inverse(x, r)), z, rtol=1e-12)
    # Near z = 0 the entries are the angles to r (tan θ = ‖z‖).
    x = PLANE.forward(jnp.asarray([1e-4, 0.0]), r)
    np.testing.assert_allclose(float(jnp.arccos(jnp.dot(x, r))), 1e-4, rtol=1e-6)


@pytest.fixture(scope="module")
def scene():
    return small_furball_scene(strands=60, size=24)


@pytest.mark.parametrize("names", [("light_color", "shininess"), ("light_direction", "light_color", "kappa")])
def test_the_fit_image_and_its_derivatives_are_the_shading_stages(scene, names):
    """The fit's image with the light (white-light images times the colour; with the
    direction fitted, plain autodiff; else the one-pass rule) equals the shading stage's at
    a light other than the scene's, and so do their derivatives in the light."""
    model = lit_fit_model(type(scene.shading))
    target = np.zeros((24 * 24, 3))
    start = start_light([scene], names, None)
    terms = model.prepare(scene, LitParams(TRUE, start), names, target, np.ones((24 * 24, 1)))
    geometry = hj.geometry_stage(scene)
    direction = jnp.asarray(TRUE_LIGHT.direction) if "light_direction" in names else None
    color = jnp.asarray(TRUE_LIGHT.color)

    def fit_image(d, c):
        return model.image(terms, LitParams(TRUE, hj.LightParams(direction=d, color=c)))

    def stage_image(d, c):
        image = hj.shading_stage(geometry, TRUE, hj.LightParams(direction=d, color=c))
        return image[..., :3].reshape(-1, 3)

    dc = jnp.asarray([0.1, -0.3, 0.2])
    args, tangents = (direction, color), (None if direction is None else dc, jnp.asarray([0.2, 0.1, -0.4]))
    if direction is None:
        f, g = (lambda c: fit_image(None, c)), (lambda c: stage_image(None, c))
        args, tangents = args[1:], tangents[1:]
    else:
        f, g = fit_image, stage_image
    out_f, jvp_f = jax.jvp(f, args, tangents)
    out_g, jvp_g = jax.jvp(g, args, tangents)
    brightest = float(np.max(np.asarray(out_g)))
    # The fit leaves out fragments behind T < FIT_TRANSMITTANCE_CUTOFF: the image moves by
    # at most that times the brightest colour (tests/fit/test_fit.py), its derivative by
    # that times the derivative's largest pixel.
    np.testing.assert_allclose(out_f, out_g, rtol=0, atol=FIT_TRANSMITTANCE_CUTOFF * brightest)
    steepest = float(np.abs(np.asarray(jvp_g)).max())
    assert steepest > 0.01
    np.testing.assert_allclose(jvp_f, jvp_g, rtol=0, atol=FIT_TRANSMITTANCE_CUTOFF * steepest)
    assert np.abs(np.asarray(out_g) - np.asarray(hj.render(scene, TRUE))[..., :3].reshape(-1, 3)).max() > 0.05


@pytest.fixture(scope="module")
def flat(scene):
    """Without shadows nothing but L and the light's colour depends on the light, so the
    renderer's image at another light is the fit's model of it."""
    return scene.replace(shadows=hj.Shadows("none"))


def test_fit_recovers_the_light_direction_and_colour(flat):
    """From the scene's light, 17° off and white, the fit recovers a target's light
    direction, its colour (kd and ks held, so the colour is determined) and the shininess;
    the target is the renderer's at the true light."""
    target = np.asarray(hj.render(flat.replace(light=TRUE_LIGHT), TRUE))
    start = hj.ShadingParams(kd=TRUE.kd, ks=TRUE.ks, shininess=10.0, kappa=TRUE.kappa, ambient=TRUE.ambient)
    r = hj.fit(flat, target, init=start, variables=("light_direction", "light_color", "shininess"))
    assert r.termination == "converged" and r.undetermined == ()
    angle = float(np.arccos(np.clip(unit(r.light.direction) @ unit(TRUE_LIGHT.direction), -1, 1)))
    start_angle = float(np.arccos(unit(r.initial_light.direction) @ unit(TRUE_LIGHT.direction)))
    assert start_angle > 0.25  # 17°
    # 1e-5: the fit stops where Gauss-Newton predicts a decrease below rtol·loss + atol,
    # atol = 1e-10 of ½‖r‖² (docs/fitting.md): residuals up to ~1.4e-5 in norm; and its
    # composites differ from the renderer's by < FIT_TRANSMITTANCE_CUTOFF = 1e-5 of the
    # brightest colour. Measured: 2e-7 (angle), 5e-7 (colour), 2e-6 (shininess).
    assert angle < 1e-5
    np.testing.assert_allclose(r.light.color, TRUE_LIGHT.color, rtol=1e-5)
    np.testing.assert_allclose(r.params.shininess, TRUE.shininess, rtol=1e-5)
    np.testing.assert_array_equal(r.params.kd, TRUE.kd)  # held
    np.testing.assert_allclose(r.get("light_color"), r.light.color)
    assert isinstance(r.std_error["light_direction"], float) and r.std_error["light_color"].shape == (3,)
    report = r.to_json()
    assert report["light"]["color"] == pytest.approx(list(TRUE_LIGHT.color), rel=1e-5)
    assert report["initial_light"]["color"] == [1.0, 1.0, 1.0]


def test_gains_at_a_held_light_are_one_linear_solve(flat):
    """With the light given and held (not fitted), the image is the shading stage's at it
    and linear in Kd and Ks: one solve, exact to rounding, from a start far off."""
    target = np.asarray(hj.render(flat.replace(light=TRUE_LIGHT), TRUE))
    start = hj.ShadingParams(
        kd=5.0, ks=1e-4, shininess=TRUE.shininess, kappa=TRUE.kappa, ambient=TRUE.ambient
    )
    held = hj.LightParams.from_light(TRUE_LIGHT)
    r = hj.fit(flat, target, init=start, variables=hj.FitVariables(("kd", "ks"), light=held))
    assert r.steps == 1 and r.termination == "converged" and r.loss[1] < 1e-12 * r.loss[0]
    # 1e-6: as tests/fit/test_fit.py's solve at the scene's light (rounding of the solve).
    np.testing.assert_allclose(r.params.kd, TRUE.kd, rtol=1e-6)
    np.testing.assert_allclose(r.params.ks, TRUE.ks, rtol=1e-6)
    np.testing.assert_array_equal(r.light.color, held.color)


def test_light_fits_that_are_refused(scene):
    target = np.zeros((24, 24, 3))
    point = scene.replace(light=hj.Light(kind="point", position=(2.0, 3.0, 2.0)))
    with pytest.raises(hj.FitError, match="point light"):
        hj.fit(point, target, variables=("light_direction",))
    assert isinstance(hj.FitError("x"), ValueError)
    sphere = hj.Occluder(center=(0.0, 0.0, 0.0), radius=0.4, color=(0.8, 0.6, 0.5))
    with pytest.raises(hj.FitError, match="occluder"):
        hj.fit(scene.replace(occluder=sphere), target, variables=("light_direction", "ks"))
    with pytest.raises(hj.FitError, match="share one light"):
        hj.fit([scene, scene.replace(light=TRUE_LIGHT)], [target, target], variables=("light_color", "ks"))
    # The colour scales every lit term, as kd and ks do: with both fitted it is degenerate.
    with pytest.raises(hj.FitError, match="degenerate"):
        hj.fit(scene, target, variables=("light_color", "kd", "ks"))
    with pytest.raises(hj.FitError, match="light_direction, light_color"):
        hj.fit(scene, target, variables=("kd", "gloss"))
