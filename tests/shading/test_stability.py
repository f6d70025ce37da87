"""Numerical stability of the shading (the shared part and the other stages:
tests/stability_helpers.py): shininess and κ at their extremes, the highlight's accuracy
at p = 10⁴, tangents parallel to the light and the view, and the guards of the Kajiya-Kay
terms and of the safe norms they use.

| case                            | test_…                                  | scene: own assertions          |
|---------------------------------|-----------------------------------------|--------------------------------|
| shininess 0.5 … 10⁴             | shininess_extremes                      | mixed, flat (b ≈ 1 at centre)  |
| b^p near its peak at p = 10⁴    | highlight_accuracy_at_p_1e4             | vs float64: ~sqrt(2p)·u bound  |
| κ 0 … 10³                       | kappa_extremes                          | mixed                          |
| T ∥ L, T ∥ V                    | tangents_parallel_to_light_and_view     | mixed: colours by hand         |

Found here: at p = 10⁴ and b ≈ 1, float32 (GL and JAX alike) erred by 2.4e-4 on `flat`
(b^p has condition number p in b, and b was rounded): fixed in
_shading.kajiya_kay_terms / specular_power and model.glsl, which carry the gap
1 − b = s²/(1 + b), s = sin(θ_L ∓ θ_V), and take b^p = exp(p·log1p(−gap)) (GLSL with its
own log1p: llvmpipe's log is inaccurate just below 1); now < 1e-6 there, ≤ 3e-5 relative
near any peak (test_highlight_accuracy_at_p_1e4, against 2.7e-3 before).

| guard (file: function)                          | test_guard_… (or test_… in full)            |
|-------------------------------------------------|---------------------------------------------|
| _vectors: safe_norm double-where                | safe_norm_at_zero                           |
| _vectors: safe_normalize (unused by renderer)   | safe_normalize_of_zero                      |
| _shading: specular_power double-where           | specular_power_at_and_below_the_cut         |
| _shading: kajiya_kay_terms double-where, b ≤ 0  | kajiya_kay_gap_on_the_far_side              |

The GLSL twins of these guards (model.glsl's safe_norm, specular_power, kajiya_kay_gap):
tests/gl/test_stability.py.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import cone
from stability_helpers import (
    ALONG_L,
    ALONG_V,
    BACKENDS,
    DEFAULT,
    EYE,
    check,
    finite,
    glsl_highlight,
    precision,
    runner_scene,
    unit_roundoff,
)

import hairjax as hj

# --- the cases -----------------------------------------------------------------------------


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("shininess", [0.5, 1e4])
@pytest.mark.parametrize("case", ["mixed", "flat"])
def test_shininess_extremes(request, backend, shininess, case):
    """p = 0.5 (b^p steep at b = 0) and p = 10⁴ (a needle highlight; in `flat` the light
    sits next to the eye, so b ≈ 1 around the centre and the float32 rounding of b matters:
    see test_highlight_accuracy_at_p_1e4)."""
    check(backend, request, case, dict(DEFAULT, shininess=shininess))


def near_peak_directions(model: str, n: int, p: float, rng) -> tuple[np.ndarray, ...]:
    """`n` float32 unit (T, L, V) around the highlight's peak: θ_L uniform in [0.05, π − 0.05],
    θ_V = θ_L + δ (mirror: π − θ_L + δ) with p(1 − cos δ) ≤ 2, i.e. b^p ≥ e⁻², and L, V at
    random azimuths about T (b depends on the angles only); the last rows have L = V (mirror:
    V = L reflected in the plane normal to T), b = 1 up to the rounding to float32."""
    t = rng.normal(size=(n, 3))
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    e1 = rng.normal(size=(n, 3))
    e1 -= np.sum(e1 * t, axis=1, keepdims=True) * t
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(t, e1)
    theta_l = rng.uniform(0.05, np.pi - 0.05, n)
    delta = rng.uniform(-1.0, 1.0, n) * np.arccos(1 - 2 / p)
    delta[-8:] = 0.0
    theta_v = theta_l + delta if model == "kajiya-kay" else np.pi - theta_l + delta

    def direction(theta, phi):
        around = np.cos(phi)[:, None] * e1 + np.sin(phi)[:, None] * e2
        return np.cos(theta)[:, None] * t + np.sin(theta)[:, None] * around

    phi_l, phi_v = rng.uniform(0.0, 2 * np.pi, (2, n))
    phi_v[-8:] = phi_l[-8:]
    return tuple(x.astype(np.float32) for x in (t, direction(theta_l, phi_l), direction(theta_v, phi_v)))


def highlight_by_angles(t, light, eye, model: str, p: float) -> np.ndarray:
    """max(b, 0)^p in float64 for the directions of the (float32) vectors, from the angles:
    b = cos Δ, Δ = θ_L − θ_V (kajiya-kay) or θ_L + θ_V − π (mirror: −cos(θ_L + θ_V)), so
    1 − b = 2 sin²(Δ/2) without cancellation. The vectors are normalised first: the model is
    defined for unit vectors, and their float32 norms 1 ± u would move b by O(u) — the very
    error under test (float64 rendering sees unit vectors to 1e-16)."""
    t, light, eye = (np.asarray(x, np.float64) for x in (t, light, eye))
    t, light, eye = (x / np.linalg.norm(x, axis=1, keepdims=True) for x in (t, light, eye))

    def angle(x):
        return np.arctan2(np.linalg.norm(np.cross(t, x), axis=1), np.sum(t * x, axis=1))

    delta = angle(light) - angle(eye) if model == "kajiya-kay" else angle(light) + angle(eye) - np.pi
    gap = 2 * np.sin(delta / 2) ** 2
    return np.where(gap < 1, np.exp(p * np.log1p(-np.minimum(gap, 1.0))), 0.0)


@pytest.mark.parametrize("model", ["kajiya-kay", "kajiya-kay-mirror"])
@pytest.mark.parametrize("backend", ["float32", "gl"])
def test_highlight_accuracy_at_p_1e4(request, backend, model):
    """b^p at p = 10⁴ near its peak (b^p ≥ e⁻²), in float32 — kajiya_kay_terms +
    specular_power in JAX, shade_point in GLSL — against the model in float64 at the same
    float32 directions, to the bound below; and the old exp(p·log b), b rounded in float32,
    fails that bound (the control: the gap 1 − b = s²/(1 + b) is what makes the difference).
    The errors are printed (pytest -s).

    The bound, u = 2⁻²⁴: with s = sin(θ_L ∓ θ_V), g = 1 − b = s²/(1 + b), x = p·g ≈ −ln b^p ≤ 2:
    - cos θ = T·X errs by ≤ 3u, sin θ = ‖T × X‖ by ≤ 6u (3u the cross product, 2.5u the
      norm), so s = sin θ_L cos θ_V ∓ cos θ_L sin θ_V by |δs| ≤ 6u(|cos θ_L| + |cos θ_V|) +
      3u(sin θ_L + sin θ_V) + 2u ≤ (2√45 + 2)u < 16u (absolute: s → 0 at the peak);
    - g then errs by 2|δs|/|s| relative, plus ~12u (the square, 1 + b, the division, the
      inputs' norms 1 ± u scaling s² and 1 + b alike), and b^p = exp(p·log1p(−g)) by
      p·δg plus a few u·(x + 1) (log1p, the product, exp: GLSL allows 3 + 2x ulps);
    - p·g·2|δs|/|s| = 2x|δs|/|s| and |s| = sqrt(g(1 + b)) ≈ sqrt(2x/p) give
      relative error ≤ 16u·sqrt(2p·x) + 64u ≤ 32u·sqrt(p) + 64u = 1.95e-4 (x ≤ 2, p = 10⁴).
    Rounding b itself (the old formula) errs by p·|δb| with |δb| a few u: ~1e-3."""
    from hairjax._shading import kajiya_kay_terms, specular_power

    p = 1e4
    u = unit_roundoff(np.float32)
    bound = 32 * u * np.sqrt(p) + 64 * u
    t, light, eye = near_peak_directions(model, 4096, p, np.random.default_rng(11))
    exact = highlight_by_angles(t, light, eye, model, p)
    assert exact.min() >= np.exp(-2.0) * (1 - 1e-9)
    if backend == "gl":
        got = glsl_highlight(request.getfixturevalue("gl"), t, light, eye, model, p)[:, 0]
    else:
        with precision("float32"):
            power = jax.jit(
                jax.vmap(
                    lambda a, b, c: specular_power(kajiya_kay_terms(a, b, c, cone(model))[1], jnp.float32(p))
                )
            )
            got = np.asarray(power(t, light, eye))
        assert got.dtype == np.float32
    err = np.max(np.abs(got.astype(np.float64) - exact) / exact)
    # The control: b = (T·L)(T·V) ± sin sin rounded in float32, then exp(p·log b) in float32.
    tl, tv = np.sum(t * light, axis=1), np.sum(t * eye, axis=1)
    sl, sv = (np.linalg.norm(np.cross(t, x), axis=1) for x in (light, eye))
    b = tl * tv + sl * sv if model == "kajiya-kay" else sl * sv - tl * tv
    assert b.dtype == np.float32
    old = np.exp(np.float32(p) * np.log(b))
    old_err = np.max(np.abs(old.astype(np.float64) - exact) / exact)
    print(
        f"\n{backend} {model}, p = 1e4, b^p ≥ e^-2: max relative error {err:.3g} "
        f"(bound {bound:.3g}); old exp(p·log b) in float32: {old_err:.3g}"
    )
    assert err <= bound, (err, bound)
    assert old_err > bound, (old_err, bound)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("kappa", [0.0, 1e3])
def test_kappa_extremes(request, backend, kappa):
    """κ = 0 (no shadow) and κ = 10³ (τ underflows to 0 wherever Ω > 0.75)."""
    check(backend, request, "mixed", dict(DEFAULT, kappa=kappa))


def kajiya_kay_by_hand(t, light, eye):
    """(sin(T, L), b) of docs/model.md §8 (the seed's model) for unit T, L, V, in NumPy."""
    sin_tl, sin_tv = np.linalg.norm(np.cross(t, light)), np.linalg.norm(np.cross(t, eye))
    return sin_tl, (t @ light) * (t @ eye) + sin_tl * sin_tv


@pytest.mark.parametrize("backend", BACKENDS)
def test_tangents_parallel_to_light_and_view(request, backend):
    """T ∥ L: sin(T, L) = ‖T × L‖ = 0 exactly (safe_norm's guard), so no diffuse light and
    b = (T·L)(T·V). T ∥ V (a strand on the camera axis, drawn as nothing but shaded): b =
    (T·L)(T·V) = 0 here. The point colours equal those values by hand; the gradients are
    finite although safe_norm sits at its kink (check_jax); GL draws the T ∥ L strand as
    JAX does (check_gl)."""
    _, res = check(backend, request, "mixed")
    if backend == "gl":
        return
    dtype = backend
    scene = runner_scene("mixed")
    s, pts, c = scene.strands, scene.strands.points, scene.strands.color
    light = np.array([0.0, 1.0, 0.0])
    rgb = np.asarray(scene.light.color)
    p = DEFAULT["shininess"]
    tau = np.exp(-DEFAULT["kappa"] * res.omega)
    # b^p amplifies b's rounding by p; every other factor carries a few roundings.
    rtol = 16 * (p + 4) * unit_roundoff(np.dtype(dtype))
    for strand, tangent in ((ALONG_L, np.array([0.0, -1.0, 0.0])), (ALONG_V, np.array([0.0, 0.0, 1.0]))):
        for i in range(s.offsets[strand], s.offsets[strand + 1]):
            eye = (EYE - pts[i]) / np.linalg.norm(EYE - pts[i])
            sin_tl, b = kajiya_kay_by_hand(tangent, light, eye)
            expected = DEFAULT["ambient"] * c[i] + tau[i] * rgb * (
                DEFAULT["kd"] * sin_tl * c[i] + DEFAULT["ks"] * max(b, 0.0) ** p
            )
            np.testing.assert_allclose(res.colors[i], expected, rtol=rtol, atol=rtol)
    # Seen from the light, the strand along L is a row of zero-length ribbons: it draws
    # nothing there and casts no shadow, not even on itself.
    np.testing.assert_array_equal(res.omega[s.offsets[ALONG_L] : s.offsets[ALONG_L + 1]], 0.0)


# --- the guards ----------------------------------------------------------------------------
# One test per guard (the table in the module docstring): inputs that make it fire, and the
# guarded result checked against the model's value.


@pytest.mark.parametrize("dtype", ["float64", "float32"])
def test_guard_safe_norm_at_zero(dtype):
    """_vectors.safe_norm's double-where: ‖0‖ = 0 with gradient 0 (not NaN); in float64
    below SAFE_NORM_EPS too (in float32 SAFE_NORM_EPS² underflows: only exact zeros fire,
    as in GLSL). Reached in the renderer by T ∥ L, T ∥ V and zero tangents: sin = 0 and a
    finite gradient with respect to the tangent."""
    from hairjax._constants import SAFE_NORM_EPS
    from hairjax._vectors import safe_norm

    with precision(dtype):
        for v in ([0.0, 0.0, 0.0], [0.0, 1e-31, 0.0] if dtype == "float64" else [0.0, 0.0, 0.0]):
            x = jnp.asarray(v)
            value, grad = jax.value_and_grad(safe_norm)(x)
            assert float(value) == 0.0 and np.all(np.asarray(grad) == 0.0)
        x = jnp.asarray([0.0, 1e3 * SAFE_NORM_EPS if dtype == "float64" else 1e-10, 0.0])
        assert float(safe_norm(x)) == float(x[1])  # above the cut: the norm itself
        t = jnp.asarray([0.0, 1.0, 0.0])
        params = hj.ShadingParams(kd=0.7, ks=0.5, shininess=1e4)

        def shade(t, v):
            d, s = hj.extend.kajiya_kay(t, t, v, params)  # T ∥ L
            return jnp.sum(d + s)

        grad_shade = jax.jit(jax.value_and_grad(shade))
        for v in (t, jnp.asarray([0.6, 0.8, 0.0])):  # also T ∥ V
            value, grad = grad_shade(t, v)
            assert np.isfinite(float(value)) and np.all(np.isfinite(np.asarray(grad)))
        d, _ = hj.extend.kajiya_kay(t, t, jnp.asarray([0.6, 0.8, 0.0]), params)
        np.testing.assert_array_equal(d, 0.0)


def test_guard_safe_normalize_of_zero():
    """_vectors.safe_normalize (GLSL strand.vert's twin): 0 ↦ 0 with a finite gradient."""
    from hairjax._vectors import safe_normalize

    zero = jnp.zeros(3)
    np.testing.assert_array_equal(safe_normalize(zero), 0.0)
    jac = jax.jacobian(safe_normalize)(zero)
    assert np.all(np.isfinite(np.asarray(jac)))
    np.testing.assert_allclose(safe_normalize(jnp.asarray([3.0, 0.0, 4.0])), [0.6, 0.0, 0.8], rtol=1e-15)


@pytest.mark.parametrize("dtype", ["float64", "float32"])
def test_guard_specular_power_at_and_below_the_cut(dtype):
    """_shading.specular_power's double-where: for b = 1 − gap ≤ SPECULAR_BASE_EPS (b < 0 on
    the cone's far side, b = 0 with p = 0.5 where d(b^p)/db = ∞, log 0 = −∞ in d/dp) the
    value and both gradients are exactly 0; just above the cut, b^p by hand. The jump at the
    cut: ≤ eps^0.5 = 1e-6 in float64 (the reason for the constant's value); in float32 the
    smallest base above it is 2⁻²⁴ (1 − gap with gap's resolution at 1), a jump of 2.4e-4 —
    within b^0.5's error from b's own absolute rounding (~u: b ≈ 0 is a cancelling sum)."""
    from hairjax._constants import SPECULAR_BASE_EPS
    from hairjax._shading import specular_power

    with precision(dtype):
        f = jax.value_and_grad(specular_power, argnums=(0, 1))
        one = np.dtype(dtype).type(1.0)
        # Gaps whose b = 1 − gap (exact: Sterbenz) is −0.3, 0, 1e-13, ≤ SPECULAR_BASE_EPS.
        at_cut = one - np.dtype(dtype).type(SPECULAR_BASE_EPS)
        at_cut = at_cut if one - at_cut <= SPECULAR_BASE_EPS else np.nextafter(at_cut, 2 * one)
        for gap in (one + np.dtype(dtype).type(0.3), one, one - np.dtype(dtype).type(1e-13), at_cut):
            assert one - gap <= SPECULAR_BASE_EPS
            for p in (0.5, 1e4):
                value, (gg, gp) = f(jnp.asarray(gap), jnp.asarray(p))
                assert float(value) == 0.0 and float(gg) == 0.0 and float(gp) == 0.0
        gap = min(one - np.dtype(dtype).type(2 * SPECULAR_BASE_EPS), np.nextafter(one, 0 * one))
        b = float(one - gap)  # 2e-12 in float64, 2⁻²⁴ in float32
        assert b > SPECULAR_BASE_EPS
        value, (gg, gp) = f(jnp.asarray(gap), jnp.asarray(0.5))
        u = unit_roundoff(np.dtype(dtype))
        # exp(p·log1p(−gap)): log1p and the product carry a few ulps, times |p·log b| ≤ 13.5.
        np.testing.assert_allclose(float(value), np.sqrt(b), rtol=64 * u)
        np.testing.assert_allclose(float(gg), -0.5 / np.sqrt(b), rtol=64 * u)
        np.testing.assert_allclose(float(gp), np.sqrt(b) * np.log(b), rtol=64 * u)
        assert np.sqrt(SPECULAR_BASE_EPS) <= 1e-6
        assert float(value) <= np.sqrt(max(2 * SPECULAR_BASE_EPS, 2 * u)) * (1 + 64 * u)


@pytest.mark.parametrize("dtype", ["float64", "float32"])
def test_guard_kajiya_kay_gap_on_the_far_side(dtype):
    """_shading.kajiya_kay_terms' double-where: where b ≤ 0 the gap is 1 − b, not
    s²/(1 + b), which is 0/0 at b = −1 (kajiya-kay: T ∥ L, V = −T; mirror: T ∥ L ∥ V) — and
    its gradient NaN. There, and at b = 0 (T ⟂ L, T ∥ V) and b = −0.75: gap = 1 − b by hand,
    b^p = 0 and every gradient (T, L, V, p) exactly 0."""
    from hairjax._shading import kajiya_kay_terms, specular_power

    x, y = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
    w = np.array([0.6614378, 0.75, 0.0])  # T·w = 0.75 for T = y (w unit to 1e-8; exact b)
    cases = [
        ("kajiya-kay", x, x, -x, -1.0),
        ("kajiya-kay-mirror", x, x, x, -1.0),
        ("kajiya-kay", x, y, x, 0.0),
        ("kajiya-kay", y, w, -y, -0.75),
        ("kajiya-kay-mirror", y, w, y, -0.75),
    ]
    with precision(dtype):
        for model, t, light, eye, b in cases:
            t, light, eye = (jnp.asarray(a) for a in (t, light, eye))

            def power(t, light, eye, p, model=model):
                return specular_power(kajiya_kay_terms(t, light, eye, cone(model))[1], p)

            _, gap = kajiya_kay_terms(t, light, eye, cone(model))
            assert float(gap) == 1.0 - b, (model, float(gap), b)
            value, grads = jax.value_and_grad(power, argnums=(0, 1, 2, 3))(t, light, eye, jnp.asarray(1e4))
            assert float(value) == 0.0
            assert all(np.all(np.asarray(g) == 0.0) for g in grads), (model, grads)
            grad_gap = jax.grad(
                lambda t, light, eye, model=model: kajiya_kay_terms(t, light, eye, cone(model))[1],
                argnums=(0, 1, 2),
            )(t, light, eye)
            assert finite(grad_gap)
