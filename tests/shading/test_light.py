"""The light as an input of the shading stage (docs/model.md §3): `LightParams`, the image
without it, with it, and its derivatives."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import small_furball_scene

import hairjax as hj
from hairjax._shading._light import directional_to_light

NEW = hj.Light(direction=(0.3, -0.8, -0.5), color=(1.0, 0.7, 0.4))


@pytest.fixture(scope="module")
def scene():
    return small_furball_scene(strands=60, size=24)


@pytest.fixture(scope="module")
def occluder_scene():
    sphere = hj.Occluder(center=(0.0, 0.0, 0.0), radius=0.4, color=(0.8, 0.6, 0.5))
    return small_furball_scene(strands=60, size=24, occluder=sphere)


def test_without_a_light_the_image_is_todays(scene, occluder_scene):
    """light=None is the geometry's light, bit for bit; the scene's own light as
    LightParams gives the same image to rounding (L normalised in JAX instead of NumPy)."""
    for s in (scene, occluder_scene):
        geometry = hj.geometry_stage(s)
        today = np.asarray(hj.render(s))
        np.testing.assert_array_equal(np.asarray(hj.shading_stage(geometry, s.params, None)), today)
        np.testing.assert_array_equal(np.asarray(hj.shading_stage(geometry, s.params)), today)
    geometry = hj.geometry_stage(scene)
    own = np.asarray(hj.shading_stage(geometry, scene.params, hj.LightParams.from_light(scene.light)))
    # 1e-14: a few float64 ulps of colours ≤ 1 (L differs from NumPy's by its rounding).
    np.testing.assert_allclose(own, np.asarray(hj.render(scene)), rtol=0, atol=1e-14)
    # A point light's parameters are its colour alone: its L stays the geometry's.
    point = scene.replace(light=hj.Light(kind="point", position=(2.0, 3.0, 2.0), color=(0.9, 0.8, 0.7)))
    params = hj.LightParams.from_light(point.light)
    assert params.direction is None
    point_geometry = hj.geometry_stage(point)
    np.testing.assert_array_equal(
        np.asarray(hj.shading_stage(point_geometry, point.params, params)), np.asarray(hj.render(point))
    )


def test_a_given_light_is_the_scene_rendered_at_it(scene, occluder_scene):
    """Without shadows nothing else depends on the light, so the shading stage with a new
    light equals the scene rendered at that light; with an occluder and shadows, a new
    colour changes neither Ω nor V (§7, §13), so the same holds for the colour (the
    occluder's Lambert term follows it)."""
    flat = scene.replace(shadows=hj.Shadows("none"))
    got = hj.shading_stage(hj.geometry_stage(flat), flat.params, hj.LightParams.from_light(NEW))
    want = hj.render(flat.replace(light=NEW))
    # 1e-14: rounding, as above; the new light moves the image by far more.
    np.testing.assert_allclose(np.asarray(got), np.asarray(want), rtol=0, atol=1e-14)
    assert np.abs(np.asarray(want) - np.asarray(hj.render(flat))).max() > 0.1
    recoloured = occluder_scene.replace(
        light=hj.Light(direction=occluder_scene.light.direction, color=NEW.color)
    )
    got = hj.shading_stage(
        hj.geometry_stage(occluder_scene), occluder_scene.params, hj.LightParams(color=NEW.color)
    )
    np.testing.assert_allclose(np.asarray(got), np.asarray(hj.render(recoloured)), rtol=0, atol=1e-14)


def test_what_is_refused(occluder_scene):
    with pytest.raises(ValueError, match="occluder"):
        hj.shading_stage(
            hj.geometry_stage(occluder_scene), occluder_scene.params, hj.LightParams(direction=NEW.direction)
        )
    with pytest.raises(hj.SceneError, match="light.direction"):
        hj.LightParams(direction=(0.0, 0.0, 0.0))
    with pytest.raises(hj.SceneError, match="light.color"):
        hj.LightParams(color=(1.0, -0.1, 1.0))


def test_zero_direction_gives_no_light_not_nan():
    """The guard in `directional_to_light`: L = 0 and a zero gradient at a zero direction
    (refused at construction, but reachable by a caller's own traced values)."""
    zero = jnp.zeros(3)
    np.testing.assert_array_equal(np.asarray(directional_to_light(zero)), 0.0)
    grad = jax.jacfwd(directional_to_light)(zero)
    assert np.all(np.isfinite(np.asarray(grad)))


def _central(f, x, v, eps):
    return (np.asarray(f(x + eps * v)) - np.asarray(f(x - eps * v))) / (2 * eps)


def test_image_derivatives_in_the_light_match_central_differences(scene, occluder_scene):
    """Forward-mode derivatives of the image (every pixel) along random directions in the
    light's direction and colour against float64 central differences; the colour also
    with an occluder, whose Lambert term is linear in it, and in reverse mode."""
    rng = np.random.default_rng(7)
    geometry = hj.geometry_stage(scene)
    d0, c0 = jnp.asarray(scene.light.direction), jnp.asarray(NEW.color)

    def by_direction(d):
        return hj.shading_stage(geometry, scene.params, hj.LightParams(direction=d, color=c0))

    v = jnp.asarray(rng.normal(size=3))
    jvp = np.asarray(jax.jvp(by_direction, (d0,), (v,))[1])
    assert np.abs(jvp).max() > 0.1
    eps = 1e-4
    fd, fd2 = _central(by_direction, d0, v, eps), _central(by_direction, d0, v, 2 * eps)
    # Tolerance from the difference itself: a central difference errs by Cε² + O(ε⁴), so
    # fd2 − fd = 3Cε² and the error at ε is |fd2 − fd|/3 to leading order (measured on this
    # scene: 2.5e-9, as the estimate; we allow twice it), plus float64 rounding of the images,
    # ~u·max|image|/ε ≈ 1e-12 (allowed: 1e-11).
    bound = 2 * np.abs(fd2 - fd).max() / 3 + 1e-11
    assert np.abs(fd - jvp).max() <= bound, (np.abs(fd - jvp).max(), bound)

    occ_geometry = hj.geometry_stage(occluder_scene)

    def by_color(c):
        return hj.shading_stage(occ_geometry, occluder_scene.params, hj.LightParams(color=c))

    w = jnp.asarray(rng.normal(size=3))
    jvp = np.asarray(jax.jvp(by_color, (c0,), (w,))[1])
    # The image is linear in the colour: the central difference has no truncation error,
    # only rounding, ~u·max|image|/ε = 1e-15 at ε = 0.1 (allowed: 1e-12).
    np.testing.assert_allclose(_central(by_color, c0, w, 0.1), jvp, rtol=0, atol=1e-12)
    occluded = np.asarray(occ_geometry.occluder_pixel)
    assert np.abs(jvp.reshape(-1, 4)[occluded, :3]).max() > 0.01  # the occluder follows the colour

    weights = jnp.asarray(rng.normal(size=jvp.shape))
    grad = jax.grad(lambda c: jnp.sum(weights * by_color(c)))(c0)
    np.testing.assert_allclose(float(grad @ w), float(np.sum(np.asarray(weights) * jvp)), rtol=1e-12)
