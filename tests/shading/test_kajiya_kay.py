"""Kajiya-Kay (docs/model.md §8) against hand-computed values."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import cone

from hairjax import ShadingParams
from hairjax._shading import kajiya_kay_terms, specular_power
from hairjax.extend import kajiya_kay

PARAMS = ShadingParams(kd=(0.5, 0.25, 1.0), ks=2.0, shininess=3.0)


def unit(*v):
    v = np.asarray(v, dtype=np.float64)
    return jnp.asarray(v / np.linalg.norm(v))


def test_known_vectors_both_conventions():
    # T = x; L at 60° from T, V at 30° from T, both in the xy plane, same side.
    T = unit(1, 0, 0)
    L = unit(np.cos(np.pi / 3), np.sin(np.pi / 3), 0)
    V = unit(np.cos(np.pi / 6), np.sin(np.pi / 6), 0)
    d, s = kajiya_kay(T, L, V, PARAMS, cone("kajiya-kay"))
    # diffuse = Kd sin 60°; seed's base = cos(60° − 30°) = cos 30°.
    np.testing.assert_allclose(d, np.array([0.5, 0.25, 1.0]) * np.sqrt(3) / 2, rtol=1e-14)
    np.testing.assert_allclose(s, 2.0 * (np.sqrt(3) / 2) ** 3, rtol=1e-13)
    d, s = kajiya_kay(T, L, V, PARAMS, cone("kajiya-kay-mirror"))
    # mirror base = −cos(60° + 30°) = 0: no highlight.
    np.testing.assert_allclose(s, 0.0, atol=1e-14)
    # V at 120° from T (the mirror direction of L at 60°): mirror base = −cos 180° = 1.
    V2 = unit(np.cos(2 * np.pi / 3), np.sin(2 * np.pi / 3), 0)
    _, s = kajiya_kay(T, L, V2, PARAMS, cone("kajiya-kay-mirror"))
    np.testing.assert_allclose(s, 2.0, rtol=1e-13)
    _, s = kajiya_kay(T, L, V2, PARAMS, cone("kajiya-kay"))
    # seed's base = cos(60° − 120°) = ½.
    np.testing.assert_allclose(s, 2.0 * 0.5**3, rtol=1e-13)


@pytest.mark.parametrize("model, peak_offset", [("kajiya-kay", 0.0), ("kajiya-kay-mirror", None)])
def test_where_each_model_peaks(model, peak_offset):
    """Sweep V's angle to T: the seed's model peaks at θ_V = θ_L (retro-reflection cone),
    the mirror model at θ_V = π − θ_L (specular cone)."""
    theta_l = 0.7
    T = unit(1, 0, 0)
    L = unit(np.cos(theta_l), np.sin(theta_l), 0)
    thetas = np.linspace(0.01, np.pi - 0.01, 2001)
    V = jnp.stack([jnp.cos(thetas), jnp.sin(thetas), jnp.zeros_like(thetas)], axis=1)
    p = ShadingParams(kd=0.0, ks=1.0, shininess=50.0)
    spec = jax.vmap(lambda v: kajiya_kay(T, L, v, p, cone(model))[1][0])(V)
    expected = theta_l if model == "kajiya-kay" else np.pi - theta_l
    # The sweep's step is π/2000 ≈ 1.6e-3 rad.
    assert abs(thetas[int(jnp.argmax(spec))] - expected) < 2e-3
    assert float(spec.max()) == pytest.approx(1.0, abs=1e-5)


def test_sine_is_exact_near_zero():
    # T almost parallel to L: sin = 1e-9 exactly representable via the cross product,
    # while sqrt(1 − cos²) would return 0 in float64.
    T = unit(1, 0, 0)
    L = jnp.asarray([1.0, 1e-9, 0.0]) / np.sqrt(1 + 1e-18)
    d, _ = kajiya_kay(T, L, T, ShadingParams(kd=1.0, ks=0.0), cone("kajiya-kay"))
    np.testing.assert_allclose(d, 1e-9, rtol=1e-6)


def test_power_finite_at_zero_base_and_large_exponent():
    # specular_power takes the gap 1 − b (kajiya_kay_terms' second value).
    for base in (0.0, 1e-300, 0.5, 1.0):
        for p in (0.5, 1.0, 1e4):
            val, grads = jax.value_and_grad(specular_power, argnums=(0, 1))(
                jnp.asarray(1.0 - base), jnp.asarray(p)
            )
            assert np.isfinite(val) and all(np.isfinite(g) for g in grads)
    assert specular_power(jnp.asarray(1.0), jnp.asarray(3.0)) == 0.0  # b = 0
    assert specular_power(jnp.asarray(1.3), jnp.asarray(3.0)) == 0.0  # b = −0.3
    assert specular_power(jnp.asarray(0.0), jnp.asarray(1e4)) == 1.0  # b = 1
    np.testing.assert_allclose(specular_power(jnp.asarray(0.5), jnp.asarray(3.0)), 0.125)


def test_gradients_finite_for_tangent_parallel_to_light_and_view():
    T = unit(0, 1, 0)

    def f(p, t):
        d, s = kajiya_kay(t, T, T, p, cone("kajiya-kay"))
        return jnp.sum(d + s)

    params = ShadingParams(kd=0.3, ks=0.7, shininess=1e4)
    gp, gt = jax.grad(f, argnums=(0, 1))(params, T)
    for leaf in jax.tree_util.tree_leaves((gp, gt)):
        assert np.all(np.isfinite(leaf))


def test_terms_and_power_equal_max_b_0_to_the_p():
    """specular_power(kajiya_kay_terms(...)[1], p) = max(b, 0)^p with b from its definition
    (docs/model.md §8), for random unit vectors (b all over [−1, 1]) and both models; and
    the gap equals 1 − b (float64: agreement to rounding)."""
    rng = np.random.default_rng(3)
    vecs = rng.normal(size=(3, 500, 3))
    vecs /= np.linalg.norm(vecs, axis=-1, keepdims=True)
    t, light, eye = vecs
    tl, tv = np.sum(t * light, -1), np.sum(t * eye, -1)
    sl, sv = (np.linalg.norm(np.cross(t, x), axis=-1) for x in (light, eye))
    p = 7.5
    for model, b in (("kajiya-kay", tl * tv + sl * sv), ("kajiya-kay-mirror", sl * sv - tl * tv)):
        _, gap = jax.vmap(kajiya_kay_terms, in_axes=(0, 0, 0, None))(t, light, eye, cone(model))
        np.testing.assert_allclose(gap, 1 - b, rtol=0, atol=1e-15)
        power = jax.vmap(specular_power, in_axes=(0, None))(gap, jnp.asarray(p))
        # b^p's condition number is p: 1e-15 absolute in b, ≤ p·1e-15/b relative.
        np.testing.assert_allclose(power, np.maximum(b, 0) ** p, rtol=1e-12, atol=1e-15)
        assert np.any(b < 0) and np.any(b > 0.9)


@pytest.mark.parametrize("model", ["kajiya-kay", "kajiya-kay-mirror"])
def test_gradients_finite_at_the_peak_and_beyond(model):
    """At b = 1 exactly (s = 0: T ⟂ L and T ⟂ V; L = V, or V the reflection of L in the
    plane normal to T; T ∥ L ∥ ±V) and at b ≤ 0 (b = −1, 0, −⅔), b^p and its gradients in T, L, V
    and p are finite, in float64 and float32; b^p = 1 at the peak, exactly 0 beyond."""
    T, L, Z = unit(0, 1, 0), unit(1, 0, 0), unit(0, 0, 1)
    a, a_mirror = unit(1, 2, 2), unit(1, -2, 2)  # T·a = ⅔ = −T·a_mirror
    if model == "kajiya-kay":  # b = cos(θ_L − θ_V)
        peak = [(T, L, Z), (T, a, a), (T, T, T)]
        beyond = [(T, T, -T), (T, L, T), (T, a, -T)]
    else:  # b = −cos(θ_L + θ_V)
        peak = [(T, L, Z), (T, a, a_mirror), (T, T, -T)]
        beyond = [(T, T, T), (T, L, T), (T, a, T)]

    def power(t, light, eye, p):
        return specular_power(kajiya_kay_terms(t, light, eye, cone(model))[1], p)

    for dtype in ("float64", "float32"):
        with jax.enable_x64(dtype == "float64"):
            f = jax.value_and_grad(power, argnums=(0, 1, 2, 3))
            for vecs, expected in ((peak, 1.0), (beyond, 0.0)):
                for t, light, eye in vecs:
                    args = [jnp.asarray(np.asarray(x), dtype) for x in (t, light, eye)]
                    for p in (0.5, 1e4):
                        value, grads = f(*args, jnp.asarray(p, dtype))
                        if expected == 1.0:
                            np.testing.assert_allclose(value, 1.0, rtol=1e-6)
                        else:
                            assert float(value) == 0.0
                        for g in grads:
                            assert np.all(np.isfinite(np.asarray(g))), (dtype, t, light, eye, p)


def test_specular_power_gradient_matches_finite_differences():
    b, p = 0.73, 17.0
    gap = 1 - b
    g_gap, g_p = jax.grad(specular_power, argnums=(0, 1))(jnp.asarray(gap), jnp.asarray(p))
    eps = 1e-7  # ≈ √eps_float64 · scale
    fd_gap = (specular_power(gap + eps, p) - specular_power(gap - eps, p)) / (2 * eps)
    fd_p = (specular_power(gap, p + eps) - specular_power(gap, p - eps)) / (2 * eps)
    # Central differences: truncation O(eps²), roundoff O(1e-16/eps) = 1e-9 relative.
    np.testing.assert_allclose(g_gap, fd_gap, rtol=1e-7)
    np.testing.assert_allclose(g_p, fd_p, rtol=1e-7)
    # d(b^p)/d(gap) = −d(b^p)/db = −p·b^(p−1); d/dp = b^p·log b.
    np.testing.assert_allclose(g_gap, -p * b ** (p - 1), rtol=1e-12)
    np.testing.assert_allclose(g_p, b**p * np.log(b), rtol=1e-12)


def test_scalar_parameters_broadcast_to_rgb():
    p = ShadingParams(kd=0.2, ks=0.3, ambient=0.1)
    assert p.kd.shape == (3,) and p.ks.shape == (3,) and p.ambient.shape == (3,)
    np.testing.assert_array_equal(p.kd, [0.2, 0.2, 0.2])


def test_unknown_model_raises():
    import hairjax as hj

    with pytest.raises(hj.SceneError, match="shading.model must be one of .*got 'phong'"):
        hj.extend.shading_model_class("phong")


@pytest.mark.parametrize(
    "bad",
    [
        dict(shininess=-1.0),
        dict(shininess=0.0),
        dict(kd=-0.1),
        dict(ks=(0.1, float("nan"), 0.1)),
        dict(kappa=-1.0),
        dict(ambient=float("inf")),
    ],
)
def test_parameters_are_checked_at_construction(bad):
    """The same range checks for parameters from Python as from a scene file."""
    import hairjax as hj

    name = next(iter(bad))
    with pytest.raises(hj.SceneError, match=rf"^shading\.{name} must be"):
        ShadingParams(**bad)


def test_traced_parameters_are_not_checked():
    """Under a trace the values do not exist yet: construction must not touch them."""
    out = jax.jit(lambda p: ShadingParams(shininess=p).shininess)(-1.0)
    assert float(out) == -1.0


def test_the_models_declare_the_shininess_plateau_and_range():
    """Kajiya-Kay and its mirror and lookup variants declare one plateau, the shininess
    where Ks is solved to 0, scanned at 25 values 1.5× apart from 0.5 to 10⁴ (the range
    their sliders span); Scheuermann declares no plateau, no range; none a grey gain."""
    import hairjax as hj

    for model in (hj.KajiyaKay, hj.KajiyaKayMirror, hj.KajiyaKayLookup):
        (plateau,) = model.plateaus
        assert (plateau.parameter, plateau.gain) == ("shininess", "ks")
        scan = np.asarray(plateau.scan)
        assert len(scan) == 25 and scan[0] == 0.5 and scan[-1] == pytest.approx(1e4, rel=1e-12)
        # (10⁴/0.5)^(1/24) = 1.51: "1.5× apart" (docs/fitting.md).
        np.testing.assert_allclose(scan[1:] / scan[:-1], 20000 ** (1 / 24), rtol=1e-12)
        assert model.ranges == {"shininess": (0.5, 1e4)} and model.grey == ()
    assert hj.Scheuermann.plateaus == () and hj.Scheuermann.ranges == {} and hj.Scheuermann.grey == ()
