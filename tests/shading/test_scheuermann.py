"""Scheuermann shading (docs/model.md §17, scheuermann-2004 slides 9–13): each term against
hand-computed values, which way the shifts move the highlight, gradients against finite
differences, the per-point inputs, scene-file errors, and GL against JAX. Fitting a
Scheuermann scene: tests/fit/test_scheuermann_fit.py."""

from __future__ import annotations

import warnings

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import (
    EXAMPLES,
    MAX_BAND,
    PIXEL_TOL,
    TAU_TOL,
    render_gl_with_edited_shader,
    scheuermann_scene,
    shadow_band,
    unexplained_pixels,
)

import hairjax as hj
from hairjax import geometry_stage
from hairjax._errors import EmptyViewWarning, SceneError
from hairjax._scene._file import scene_from_dict
from hairjax._shading import point_colors
from hairjax._shading._scheuermann import (
    ScheuermannParams,
    scheuermann,
    scheuermann_diffuse,
    shift_tangent,
    smoothstep_attenuation,
    strand_specular,
)
from hairjax._shading._scheuermann_inputs import (
    ScheuermannMaps,
    scheuermann_inputs,
    strand_normals,
    strand_position,
)
from hairjax.experimental import prepare

EXAMPLE = EXAMPLES / "scheuermann.toml"


def unit(*v):
    v = np.asarray(v, dtype=np.float64)
    return jnp.asarray(v / np.linalg.norm(v))


# --------------------------------------------------------------------------- terms


def test_diffuse_is_the_seeds_lerp_saturated():
    N = unit(0, 1, 0)
    # lerp(0.25, 1, x) = 0.25 + 0.75x: N·L = 1 → 1, ½ → 0.625, 0 → 0.25, −½ → −0.125 → 0.
    for nl, expected in ((1.0, 1.0), (0.5, 0.625), (0.0, 0.25), (-0.5, 0.0), (-1 / 3, 0.0)):
        L = jnp.asarray([np.sqrt(1 - nl * nl), nl, 0.0])
        np.testing.assert_allclose(scheuermann_diffuse(N, L), expected, atol=1e-15)
    # A point without tangent has N = 0: no diffuse light (not 0.25).
    assert scheuermann_diffuse(jnp.zeros(3), unit(0, 1, 0)) == 0.0


def test_shift_tangent_values():
    # T = x, N = y, shift ¾: (1, ¾)/1.25 = (0.8, 0.6); shift 0 leaves T.
    np.testing.assert_allclose(shift_tangent(unit(1, 0, 0), unit(0, 1, 0), 0.75), [0.8, 0.6, 0.0], atol=1e-15)
    np.testing.assert_allclose(shift_tangent(unit(1, 0, 0), unit(0, 1, 0), 0.0), [1, 0, 0])
    assert np.all(shift_tangent(jnp.zeros(3), jnp.zeros(3), 0.3) == 0)  # no tangent stays 0


def test_smoothstep_attenuation_values_and_gradient():
    # t = clamp(x + 1, 0, 1), t²(3 − 2t): x = −1 → 0, −½ → ¼·2 = ½, 0 and beyond → 1.
    for x, expected in ((-1.0, 0.0), (-0.5, 0.5), (-0.75, 0.15625), (0.0, 1.0), (0.5, 1.0)):
        np.testing.assert_allclose(smoothstep_attenuation(jnp.asarray(x)), expected, atol=1e-15)
    # d/dx = 6t(1 − t): 1.5 at x = −½, 0 at both clamp edges (finite, continuous).
    grad = jax.grad(smoothstep_attenuation)
    np.testing.assert_allclose(grad(jnp.asarray(-0.5)), 1.5, rtol=1e-14)
    for x in (-1.0, 0.0, -2.0, 1.0):
        assert float(grad(jnp.asarray(x))) == 0.0


def test_strand_specular_values():
    T = unit(1, 0, 0)
    c, s = np.cos(2 * np.pi / 3), np.sin(2 * np.pi / 3)
    # T·H = −½: attenuation ½, sin = √3/2, p = 4: (¾)² = 0.5625 → 0.28125.
    np.testing.assert_allclose(strand_specular(T, jnp.asarray([c, s, 0.0]), 4.0), 0.28125, rtol=1e-14)
    # T·H = +½: no attenuation → 0.5625.
    np.testing.assert_allclose(strand_specular(T, jnp.asarray([-c, s, 0.0]), 4.0), 0.5625, rtol=1e-14)
    # Peak (T ⟂ H) = 1 at any exponent; T ∥ H gives 0; zero H (L = −V) gives 0, not the peak.
    assert float(strand_specular(T, unit(0, 0, 1), 1e4)) == 1.0
    assert float(strand_specular(T, T, 3.0)) == 0.0
    assert float(strand_specular(T, jnp.zeros(3), 3.0)) == 0.0


PARAMS = ScheuermannParams(
    kd=(0.5, 0.4, 0.3),
    ambient=0.1,
    primary_color=(1.0, 0.5, 0.25),
    primary_exponent=7.0,
    primary_shift=0.0,
    secondary_color=(0.2, 0.4, 0.8),
    secondary_exponent=2.0,
    secondary_shift=1.0,
)


def test_full_point_against_hand_values():
    """T = x, N = y, L = y, V = z: H = (0, 1, 1)/√2. Primary (shift 0): T₁ = x ⟂ H → S₁ = 1.
    Secondary (shift 1): T₂ = (1, 1, 0)/√2, T₂·H = ½ → attenuation 1, sin² = ¾, p = 2 → ¾.
    Diffuse: N·L = 1 → Kd."""
    T, N, L, V = unit(1, 0, 0), unit(0, 1, 0), unit(0, 1, 0), unit(0, 0, 1)
    d, s = scheuermann(T, N, L, V, 0.0, 0.4, PARAMS)
    np.testing.assert_allclose(d, [0.5, 0.4, 0.3], rtol=1e-15)
    expected = np.array([1.0, 0.5, 0.25]) * 1.0 + 0.4 * np.array([0.2, 0.4, 0.8]) * 0.75
    np.testing.assert_allclose(s, expected, rtol=1e-14)


def test_noise_mask_scales_only_the_secondary_lobe():
    T, N, L, V = unit(1, 0, 0), unit(0, 1, 0), unit(0, 1, 0), unit(0, 0, 1)
    primary_only = PARAMS.__class__(**{**_fields(PARAMS), "secondary_color": 0.0})
    secondary_only = PARAMS.__class__(**{**_fields(PARAMS), "primary_color": 0.0})
    for mask in (0.0, 0.3, 1.0):
        d, s = scheuermann(T, N, L, V, 0.0, mask, primary_only)
        np.testing.assert_allclose(s, [1.0, 0.5, 0.25], rtol=1e-15)  # S₁ = 1, mask-free
        np.testing.assert_allclose(d, [0.5, 0.4, 0.3], rtol=1e-15)
        _, s2 = scheuermann(T, N, L, V, 0.0, mask, secondary_only)
        np.testing.assert_allclose(s2, mask * np.array([0.2, 0.4, 0.8]) * 0.75, rtol=1e-14, atol=1e-16)


def test_shift_texture_adds_to_both_shifts():
    # σ = −1 cancels the secondary shift (T₂ = x ⟂ H: S₂ = 1) and makes the primary −1
    # (T₁ = (1, −1, 0)/√2, T₁·H = −½: attenuation ½, sin² = ¾, p = 7 → ½·(¾)^3.5).
    T, N, L, V = unit(1, 0, 0), unit(0, 1, 0), unit(0, 1, 0), unit(0, 0, 1)
    _, s = scheuermann(T, N, L, V, -1.0, 1.0, PARAMS)
    expected = np.array([1.0, 0.5, 0.25]) * 0.5 * 0.75**3.5 + np.array([0.2, 0.4, 0.8])
    np.testing.assert_allclose(s, expected, rtol=1e-14)


def _fields(p):
    return {
        k: getattr(p, k)
        for k in (
            "kd",
            "ambient",
            "primary_color",
            "primary_exponent",
            "primary_shift",
            "secondary_color",
            "secondary_exponent",
            "secondary_shift",
            "kappa",
        )
    }


# --------------------------------------------------------------------------- shift direction


def _arc(n=801):
    """A strand on the unit circle in the xy plane from the top (root, φ = 0) to the side
    (tip, φ = π/2): p = (sin φ, cos φ, 0), T = (cos φ, −sin φ, 0) root→tip, and the normal
    away from the centre N = (sin φ, cos φ, 0). It curves over the centre like hair on a head."""
    phi = np.linspace(0.0, np.pi / 2, n)
    p = np.stack([np.sin(phi), np.cos(phi), np.zeros(n)], axis=1)
    t = np.stack([np.cos(phi), -np.sin(phi), np.zeros(n)], axis=1)
    return phi, p, t, p.copy()


@pytest.mark.parametrize("shift", [0.2, -0.2, 0.5])
def test_positive_shift_moves_the_highlight_towards_the_tip(shift):
    """With H at angle ψ from the top, the unshifted lobe peaks at φ = ψ (N = H). The
    shifted tangent is ⟂ H where tan(ψ − φ) = −s (T'·H ∝ sin(ψ − φ) + s cos(ψ − φ)), i.e.
    at φ = ψ + atan(s): a positive shift moves the highlight towards the tip, a negative
    one towards the root (docs/model.md §17; slide 10 says the opposite, see there)."""
    psi = 0.6
    phi, _, t, n = _arc()
    H = jnp.asarray([np.sin(psi), np.cos(psi), 0.0])
    spec = jax.vmap(lambda ti, ni: strand_specular(shift_tangent(ti, ni, shift), H, 200.0))(
        jnp.asarray(t), jnp.asarray(n)
    )
    peak = phi[int(jnp.argmax(spec))]
    # The grid step is (π/2)/800 ≈ 2e-3 rad.
    assert abs(peak - (psi + np.arctan(shift))) < 2e-3
    assert (peak > psi) == (shift > 0)


@pytest.mark.parametrize("shift", [0.25, -0.25])
def test_shift_direction_in_a_rendered_strand(shift):
    """The same through the renderer's own set-up (central-difference tangents, normals
    from `normal_center`, a far camera and a directional light, L = V = H): the brightest
    point of the strand lies at φ = ψ + atan(s), towards the tip for s > 0."""
    psi = 0.6
    phi, p, _, _ = _arc(401)
    h = np.array([np.sin(psi), np.cos(psi), 0.0])
    scene = hj.Scene(
        hj.Strands.from_list([p], alpha=1.0),
        camera=hj.Camera(
            eye=tuple(1e4 * h), target=(0.0, 0.0, 0.0), up=(0.0, 0.0, 1.0), fov=1.0, width=8, height=8
        ),
        light=hj.Light(direction=tuple(-h)),
        shading=hj.Scheuermann(
            ScheuermannParams(
                kd=0.0,
                ambient=0.0,
                primary_color=1.0,
                primary_exponent=300.0,
                primary_shift=shift,
                secondary_color=0.0,
            ),
            ScheuermannMaps(normal_center=(0.0, 0.0, 0.0), shift_noise=0.0),
        ),
        shadows=hj.Shadows("none"),
    )
    # Only the point colours are read: the arc, 1/20 pixel across at this distance, draws
    # no fragment, which the set-up reports (EmptyViewWarning); the image is not the test's.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", EmptyViewWarning)
        colours = point_colors(geometry_stage(scene), scene.params)[:, 0]
    peak = phi[int(jnp.argmax(colours))]
    # Grid step (π/2)/400 ≈ 4e-3 rad; V differs from H by ≤ 1e-4 rad (eye 10⁴ away).
    assert abs(peak - (psi + np.arctan(shift))) < 5e-3
    assert (peak > psi) == (shift > 0)


# --------------------------------------------------------------------------- per-point inputs


def test_strand_position_is_arc_length_fraction():
    strands = hj.Strands.from_list(
        [[[0, 0, 0], [1, 0, 0], [3, 0, 0]], [[5, 5, 5], [5, 5, 6]], [[1, 1, 1]], [[2, 2, 2], [2, 2, 2]]]
    )
    np.testing.assert_allclose(
        strand_position(strands.points, strands.offsets), [0, 1 / 3, 1, 0, 1, 0, 0, 0], atol=1e-15
    )


def test_strand_normals_point_away_from_the_centre():
    rng = np.random.default_rng(5)
    p = rng.normal(size=(200, 3))
    t = rng.normal(size=(200, 3))
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    centre = np.array([0.1, -0.2, 0.3])
    n = strand_normals(p, t, centre)
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, rtol=1e-14)
    np.testing.assert_allclose(np.sum(n * t, axis=1), 0.0, atol=1e-14)
    assert np.all(np.sum(n * (p - centre), axis=1) > 0)
    # A radial strand (r ∥ T) and a point at the centre still get a unit N ⟂ T; T = 0 gets 0.
    radial = strand_normals(
        np.array([[2.0, 0, 0], [0.0, 0, 0], [1.0, 1, 1]]),
        np.array([[1.0, 0, 0], [0.0, 1, 0], [0.0, 0, 0]]),
        np.zeros(3),
    )
    np.testing.assert_allclose(np.linalg.norm(radial[:2], axis=1), 1.0, rtol=1e-14)
    np.testing.assert_allclose(np.sum(radial[:2] * np.array([[1.0, 0, 0], [0.0, 1, 0]]), axis=1), 0.0)
    assert np.all(radial[2] == 0)


def test_textures_and_noise_are_sampled_along_the_strand():
    strands = hj.Strands.from_list([[[0, 0, 0], [1, 0, 0], [2, 0, 0], [4, 0, 0]]] * 2)
    maps = ScheuermannMaps(
        base_texture=((0.0, 1.0, 2.0), (1.0, 1.0, 0.0)),
        occlusion=(0.5, 1.0),
        alpha_texture=(1.0, 0.0),
        texture_seed=3,
        shift_noise=0.4,
        mask_noise=0.5,
    )
    tangent = np.tile([1.0, 0, 0], (8, 1))
    pts, factor, segment_alpha = scheuermann_inputs(strands, tangent, maps)
    u = np.array([0, 0.25, 0.5, 1.0] * 2)
    base = (1 - u)[:, None] * [0.0, 1.0, 2.0] + u[:, None] * [1.0, 1.0, 0.0]
    np.testing.assert_allclose(factor, base * (0.5 + 0.5 * u)[:, None], rtol=1e-14)
    # Segments' middles: u = ⅛, ⅜, ¾ → alpha 1 − u.
    np.testing.assert_allclose(segment_alpha, [0.875, 0.625, 0.25] * 2, rtol=1e-14)
    # σ: constant per strand, in ±0.2; m: per point, in (0.5, 1]; deterministic per seed.
    shift = np.asarray(pts.shift)
    assert np.all(shift[:4] == shift[0]) and np.all(shift[4:] == shift[4]) and shift[0] != shift[4]
    assert np.all(np.abs(shift) <= 0.2) and np.all((pts.mask > 0.5) & (pts.mask <= 1))
    again, _, _ = scheuermann_inputs(strands, tangent, maps)
    np.testing.assert_array_equal(again.mask, pts.mask)
    # The alpha texture at 1 everywhere leaves the opacity alone (no per-segment work).
    assert scheuermann_inputs(strands, tangent, ScheuermannMaps())[2] is None


def test_base_texture_and_occlusion_scale_the_colour():
    """base(u)·AO(u) multiplies the whole point colour: constant textures scale the hair's
    part of the image by their product, per channel (black background, no occluder)."""
    plain = np.asarray(hj.render(scheuermann_scene()))
    scaled = np.asarray(hj.render(scheuermann_scene(base_texture=((0.5, 0.25, 1.0),), occlusion=(0.5,))))
    np.testing.assert_allclose(scaled[..., :3], plain[..., :3] * [0.25, 0.125, 0.5], rtol=1e-12, atol=1e-15)
    np.testing.assert_array_equal(scaled[..., 3], plain[..., 3])
    assert plain[..., :3].max() > 0.05


def test_constant_alpha_texture_equals_scaled_hair_alpha():
    """The alpha texture multiplies each segment's opacity in the camera pass and in the
    shadows: a constant ½ renders as hair alpha ½ as large."""
    textured = scheuermann_scene(alpha_texture=(0.5,))
    halved = scheuermann_scene()
    halved = halved.replace(strands=halved.strands.replace(alpha=halved.strands.alpha * 0.5))
    a, b = np.asarray(hj.render(textured)), np.asarray(hj.render(halved))
    np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-15)
    assert not np.allclose(a, np.asarray(hj.render(scheuermann_scene())))


def test_kajiya_kay_scenes_build_none_of_it():
    scene = scheuermann_scene().replace(shading=hj.KajiyaKay(hj.ShadingParams()))
    assert prepare(scene).shading_inputs == hj.extend.PointInputs()
    assert geometry_stage(scene).shading_inputs is None


# --------------------------------------------------------------------------- gradients


def test_gradients_match_central_differences():
    """d(Σ w·image)/dθ for every parameter (each RGB one along a fixed direction) against
    central differences in float64. ε = 1e-6·max(1, |θ|): truncation O(ε²) ≈ 1e-12 and
    roundoff ~1e-16/ε = 1e-10 relative, so 1e-6 leaves a wide margin."""
    scene = scheuermann_scene()
    geom = geometry_stage(scene)
    weight = jnp.asarray(np.random.default_rng(0).uniform(0.5, 1.5, (24, 24, 4)))

    @jax.jit
    def loss(p):
        return jnp.sum(weight * hj.shading_stage(geom, p))

    grads = jax.grad(loss)(scene.params)
    rng = np.random.default_rng(1)
    for name, value in _fields(scene.params).items():
        direction = rng.uniform(0.5, 1.0, np.shape(value))
        eps = 1e-6 * max(1.0, float(np.max(np.abs(value))))

        def at(h, name=name, value=value, direction=direction):
            return float(loss(ScheuermannParams(**{**_fields(scene.params), name: value + h * direction})))

        fd = (at(eps) - at(-eps)) / (2 * eps)
        analytic = float(np.sum(np.asarray(getattr(grads, name)) * direction))
        assert abs(fd) > 1e-6, name  # every parameter moves this image
        np.testing.assert_allclose(analytic, fd, rtol=1e-6, err_msg=name)


# --------------------------------------------------------------------------- errors


def test_invalid_parameters_are_refused():
    hair = hj.scalp(strands=3, points=3)
    with pytest.raises(TypeError, match="takes ScheuermannParams"):
        hj.Scene(hair, shading=hj.Scheuermann()).replace(params=hj.ShadingParams())
    with pytest.raises(TypeError, match="takes ShadingParams"):
        hj.Scene(hair).replace(params=ScheuermannParams())
    for bad in (
        dict(primary_exponent=0.0),
        dict(secondary_exponent=-1.0),
        dict(primary_color=-0.1),
        dict(secondary_shift=np.nan),
        dict(kappa=-1.0),
    ):
        with pytest.raises(SceneError, match=next(iter(bad))):
            ScheuermannParams(**bad)
    for bad, key in (
        (dict(alpha_texture=(1.2,)), "alpha_texture"),
        (dict(occlusion=()), "occlusion"),
        (dict(base_texture=((1.0, 1.0),)), "base_texture"),
        (dict(mask_noise=2.0), "mask_noise"),
        (dict(shift_noise=-1.0), "shift_noise"),
        (dict(texture_seed=-1), "texture_seed"),
        (dict(normal_center=(0.0, 1.0)), "normal_center"),
    ):
        with pytest.raises(SceneError, match=key):
            ScheuermannMaps(**bad)


@pytest.mark.parametrize(
    "shading, message",
    [
        ({"model": "scheuermann", "ks": 0.3}, r"shading\.ks is not a key of model = 'scheuermann'"),
        ({"primary_shift": 0.1}, r"shading\.primary_shift is not a key of model = 'kajiya-kay'"),
        ({"model": "scheuermann", "primary_exponent": 0}, r"shading\.primary_exponent must be > 0"),
        ({"model": "scheuermann", "alpha_texture": [1, 2]}, r"shading\.alpha_texture must be"),
        ({"model": "scheuermann", "alpha_texture": [True]}, r"shading\.alpha_texture must be"),
        ({"model": "scheuermann", "base_texture": [1, 1, 1]}, r"shading\.base_texture must be"),
        ({"model": "scheuermann", "mask_noise": 1.5}, r"shading\.mask_noise must be in \[0, 1\]"),
    ],
)
def test_scene_file_errors(tmp_path, shading, message):
    data = {"hair": {"source": "scalp", "strands": 3, "points": 3}, "shading": shading}
    with pytest.raises(SceneError, match=r"^inline: " + message):
        scene_from_dict(data, tmp_path, "inline")


def test_example_scene_reads_every_key():
    scene = hj.load_scene(EXAMPLE)
    assert isinstance(scene.shading, hj.Scheuermann) and isinstance(scene.params, ScheuermannParams)
    np.testing.assert_allclose(scene.params.secondary_color, [0.35, 0.25, 0.15])
    assert float(scene.params.primary_shift) == 0.1 and float(scene.params.secondary_shift) == -0.15
    maps = scene.shading.maps
    assert maps.normal_center == (0.0, 0.0, 0.0) and maps.texture_seed == 7 and maps.alpha_texture[-1] == 0.3


# --------------------------------------------------------------------------- GL


def gl_scene():
    """The example scene's settings (all textures, occluder, shadows) on fewer strands, 64²."""
    scene = hj.load_scene(EXAMPLE)
    hair = hj.scalp(
        strands=300,
        points=12,
        seed=2,
        length=1.0,
        gravity=(0.0, -0.5, 0.0),
        radius=0.5,
        coverage=0.6,
        alpha=0.6,
    )
    cam = scene.camera
    return scene.replace(
        strands=hair,
        camera=hj.Camera(eye=cam.eye, target=cam.target, fov=cam.fov, width=64, height=64),
        shadows=hj.Shadows("opacity-maps", maps=16, resolution=64),
    )


@pytest.fixture(scope="module")
def gl_reference():
    """The scene, JAX's image, Ω and occluder light (the sphere head casts and receives)."""
    from hairjax.gl import occluder_light

    scene = gl_scene()
    geom = geometry_stage(scene)
    return (
        scene,
        np.asarray(hj.shading_stage(geom, scene.params)),
        np.asarray(geom.omega),
        occluder_light(scene, geom),
    )


def test_gl_matches_jax(gl, gl_reference):
    """Tolerances as tests/gl/test_renderer.py (hairjax/_disagreement): 1e-4 per pixel and
    per τ outside the bands that float32 boundary decisions explain."""
    from hairjax.gl import render_gl

    scene, jax_image, omega, occluder = gl_reference
    result = render_gl(scene, omega=omega, occluder=occluder)
    bad, band = unexplained_pixels(scene, result.image, jax_image)
    assert bad.size == 0, f"{bad.size} pixels differ by > {PIXEL_TOL} with no boundary nearby"
    assert band.mean() <= MAX_BAND
    # GL's own Ω: τ agrees except at points a light-side boundary explains.
    own = render_gl(scene)
    kappa = float(scene.params.kappa)
    dtau = np.abs(np.exp(-kappa * own.omega.astype(np.float64)) - np.exp(-kappa * omega))
    assert np.flatnonzero((dtau > TAU_TOL) & ~shadow_band(scene)).size == 0


def test_a_wrong_scheuermann_shader_fails_the_check(gl, gl_reference):
    """Flip the sign of the tangent shift in GLSL: the cross-check must catch it."""
    scene, jax_image, omega, occluder = gl_reference
    wrong = render_gl_with_edited_shader(
        scene, omega, "(T + shift * N)", "(T - shift * N)", occluder=occluder
    )
    bad, _ = unexplained_pixels(scene, wrong, jax_image)
    assert bad.size > 50


# --------------------------------------------------------------------------- numerics


def test_float32_power_is_accurate_near_the_peak():
    """sin(T, H)^p from the gap cos²/(1 + sin): in float32 at p = 10⁴, where the power is
    ≥ e⁻⁵ (|cos| ≤ √(10/p)), relative error ≤ 1e-4 against float64 on the same (float32)
    inputs. The error model: ~2p|cos|·u ≤ 2√(10p)·u = 3.8e-5; rounding sin itself (the
    seed's sqrt(1 − cos²)) would give ~p·u = 6e-4 and fail this."""
    p = 1e4
    rng = np.random.default_rng(7)
    cos = rng.uniform(-np.sqrt(10 / p), np.sqrt(10 / p), 300)
    t = np.tile([1.0, 0.0, 0.0], (300, 1))
    h = np.stack([cos, np.sqrt(1 - cos**2), np.zeros(300)], axis=1)
    t32, h32 = t.astype(np.float32), h.astype(np.float32)
    with jax.enable_x64(False):
        got = np.asarray(
            jax.vmap(strand_specular, in_axes=(0, 0, None))(
                jnp.asarray(t32), jnp.asarray(h32), jnp.float32(p)
            ),
            np.float64,
        )
    ref = np.asarray(
        jax.vmap(strand_specular, in_axes=(0, 0, None))(
            jnp.asarray(t32, jnp.float64), jnp.asarray(h32, jnp.float64), jnp.float64(p)
        )
    )
    assert ref.min() > np.exp(-5.5)
    np.testing.assert_allclose(got, ref, rtol=1e-4)


def test_value_and_gradients_finite_at_the_special_points():
    """At the peak (Tᵢ ⟂ H), T ∥ H, H = 0 (L = −V), N·L at the diffuse clamp, a point
    without tangent, and p = 0.5 or 10⁴: value and every parameter gradient finite, in
    float64 and float32."""
    x, y, z = unit(1, 0, 0), unit(0, 1, 0), unit(0, 0, 1)
    cases = [
        (x, y, z, z),
        (x, y, x, x),
        (x, y, y, -y),
        (x, y, unit(1, -1 / 3, 0), z),
        (jnp.zeros(3), jnp.zeros(3), y, z),
    ]

    def total(p, t, n, light, eye):
        d, s = scheuermann(t, n, light, eye, 0.0, 0.5, p)
        return jnp.sum(d + s)

    for dtype in ("float64", "float32"):
        with jax.enable_x64(dtype == "float64"):
            f = jax.jit(jax.value_and_grad(total))
            for exponent in (0.5, 1e4):
                params = jax.tree.map(
                    lambda a: jnp.asarray(a, dtype),
                    ScheuermannParams(
                        primary_exponent=exponent,
                        secondary_exponent=exponent,
                        primary_shift=0.0,
                        secondary_shift=0.0,
                    ),
                )
                for t, n, light, eye in cases:
                    args = [jnp.asarray(np.asarray(a), dtype) for a in (t, n, light, eye)]
                    value, grads = f(params, *args)
                    assert np.isfinite(float(value))
                    for leaf in jax.tree_util.tree_leaves(grads):
                        assert np.all(np.isfinite(np.asarray(leaf))), (dtype, exponent, t, light, eye)


def test_a_scene_may_hold_traced_parameters():
    """A Scene built inside a trace (e.g. under jax.grad) cannot check values it does not
    have yet; it must not fail on them."""
    base = scheuermann_scene(size=8, strands=3, shadows="none")

    def f(shift):
        params = ScheuermannParams(**{**_fields(base.params), "primary_shift": shift})
        return jnp.sum(hj.render(base.replace(params=params)))

    assert np.isfinite(float(jax.grad(f)(0.1)))


# --------------------------------------------------------------------------- hair occlusion


def test_numpy_exact_omega_equals_the_renderers():
    """`ExactShadows.omega_numpy` (hair_occlusion's Ω) against `exact_opacity` (the
    renderer's `exact` Ω, float64) on the same light-space set-up: equal to rounding."""
    from hairjax._geometry._shadows import ShadowInputs, exact_opacity

    s = scheuermann_scene(strands=60).strands
    segs = s.segments()
    light = hj.Light(direction=(0.3, -1.0, 0.2))
    inputs = ShadowInputs(s.points, segs, s.strand_of_point[segs[:, 0]], s.width, light)
    method = hj.Shadows("exact", resolution=32)
    setup = method.setup(inputs)
    alpha = s.alpha[setup.frag_strand] * setup.frag_coverage
    ref = np.asarray(
        jax.jit(exact_opacity)(
            jnp.asarray(alpha),
            jnp.asarray(setup.frag_first),
            jnp.asarray(setup.index),
            jnp.asarray(setup.weight),
        )
    )
    assert ref.max() > 1.0  # the points are really occluded
    np.testing.assert_allclose(method.omega_numpy(setup, s.alpha), ref, rtol=1e-12, atol=1e-12)


def test_hair_occlusion_darkens_the_inside_of_the_hair():
    """A dense clump and, far from it, one lone strand: the clump's centre is occluded
    from every direction, the lone strand from almost none; values in (0, 1]; a denser
    κ_ao darkens; κ_ao = 0 computes nothing."""
    from hairjax._shading._scheuermann_inputs import hair_occlusion

    rng = np.random.default_rng(2)
    clump = [rng.normal(scale=0.15, size=(4, 3)) for _ in range(150)]
    lone = [np.array([[5.0, 0, 0], [5.0, 0.2, 0], [5.0, 0.4, 0]])]
    strands = hj.Strands.from_list(clump + lone, alpha=0.5)
    ao = hair_occlusion(strands, 1.0)
    assert np.all((ao > 0) & (ao <= 1))
    centre = np.argsort(np.linalg.norm(strands.points[:600], axis=1))[:20]
    assert ao[centre].mean() < 0.5 and ao[600:].min() > 0.8
    assert np.all(hair_occlusion(strands, 3.0)[centre] < ao[centre])
    maps = ScheuermannMaps()
    assert maps.hair_occlusion == 0  # default off; scheuermann_inputs then skips it:
    _, factor, _ = scheuermann_inputs(strands, np.tile([0.0, 1, 0], (strands.num_points, 1)), maps)
    assert np.all(factor == 1)


def test_gl_matches_jax_point_light(gl):
    """A point light (L varies per point, so H does) with `exact` shadows, default textures."""
    from hairjax.gl import render_gl

    scene = scheuermann_scene(size=48, strands=80, shadows="exact").replace(
        light=hj.Light(kind="point", position=(1.2, 1.5, 1.8))
    )
    geom = geometry_stage(scene)
    jax_image = np.asarray(hj.shading_stage(geom, scene.params))
    result = render_gl(scene, omega=np.asarray(geom.omega))
    bad, band = unexplained_pixels(scene, result.image, jax_image)
    assert bad.size == 0 and band.mean() <= MAX_BAND
    assert jax_image[..., :3].max() > 0.1


def test_equals_the_seeds_shader_on_random_inputs():
    """slide 12's HairLighting ported to NumPy line by line (normalize, sqrt(1 − dotTH²),
    pow, smoothstep, lerp, saturate) is the oracle for `scheuermann` on random unit T, L, V,
    N ⟂ T, shifts, texture values and masks (float64: agreement to rounding; the seed's
    sqrt(1 − cos²) is exact enough at these exponents)."""
    rng = np.random.default_rng(11)
    n = 400

    def units(k):
        v = rng.normal(size=(k, 3))
        return v / np.linalg.norm(v, axis=1, keepdims=True)

    t, light, eye = units(n), units(n), units(n)
    nrm = units(n)
    nrm -= np.sum(nrm * t, axis=1, keepdims=True) * t
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    shift_tex, mask = rng.uniform(-0.5, 0.5, n), rng.uniform(0, 1, n)
    p = PARAMS

    def normalize(x):
        return x / np.linalg.norm(x, axis=-1, keepdims=True)

    def strand_specular_seed(T, V, L, exponent):
        H = normalize(L + V)
        dot_th = np.sum(T * H, axis=-1)
        sin_th = np.sqrt(1.0 - dot_th * dot_th)
        x = np.clip((dot_th + 1.0) / 1.0, 0, 1)
        dir_atten = x * x * (3 - 2 * x)  # smoothstep(−1, 0, dot(T, H))
        return dir_atten * sin_th**exponent

    t1 = normalize(t + (float(p.primary_shift) + shift_tex)[:, None] * nrm)
    t2 = normalize(t + (float(p.secondary_shift) + shift_tex)[:, None] * nrm)
    nl = np.sum(nrm * light, axis=1)
    diffuse = np.clip(0.25 + nl * (1.0 - 0.25), 0, 1)[:, None] * np.asarray(p.kd)
    s1 = strand_specular_seed(t1, eye, light, float(p.primary_exponent))
    s2 = strand_specular_seed(t2, eye, light, float(p.secondary_exponent))
    specular = (
        np.asarray(p.primary_color) * s1[:, None] + np.asarray(p.secondary_color) * (mask * s2)[:, None]
    )
    d, s = jax.vmap(scheuermann, in_axes=(0, 0, 0, 0, 0, 0, None))(
        *(jnp.asarray(x) for x in (t, nrm, light, eye, shift_tex, mask)), p
    )
    np.testing.assert_allclose(d, diffuse, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(s, specular, rtol=1e-9, atol=1e-13)
    assert specular.max() > 0.5 and np.mean(specular[:, 0] > 1e-3) > 0.2  # lobes are hit


def test_opacity_gradient_with_alpha_texture_matches_central_differences():
    """The alpha texture scales coverage, so the image stays differentiable in the strand
    opacity a (geometry stage): d(Σ w·image)/da along a fixed direction against central
    differences (float64; ε = 1e-6, error budget as in the parameter test)."""
    scene = scheuermann_scene(size=16, strands=12, alpha_texture=(1.0, 0.8, 0.2))
    weight = jnp.asarray(np.random.default_rng(3).uniform(0.5, 1.5, (16, 16, 4)))
    direction = jnp.asarray(np.random.default_rng(4).uniform(-1.0, 1.0, 12))
    a0 = jnp.asarray(scene.strands.alpha)

    def loss(a):
        return jnp.sum(weight * hj.render(scene, alpha=a))

    analytic = float(jnp.dot(jax.grad(loss)(a0), direction))
    eps = 1e-6
    fd = (float(loss(a0 + eps * direction)) - float(loss(a0 - eps * direction))) / (2 * eps)
    assert abs(fd) > 1e-3
    np.testing.assert_allclose(analytic, fd, rtol=1e-6)
