"""Dual scattering for the `marschner` model (Zinke et al. 2008; docs/model.md §19,
hairjax/_shading/_dual_scattering.py): its tables against a brute-force integration of the
model's own lobes, what it adds with no fibre in front, τ kept off the scattered light,
gradients against float64 central differences, finite values at the extremes, the scene
file's option, and the fit's image of it.

The conftest runs JAX in float64."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import fit_terms, small_furball_scene

import hairjax as hj
from hairjax._constants import EUMELANIN_SIGMA_A, PHEOMELANIN_SIGMA_A
from hairjax._shading import Marschner, MarschnerParams, ShadingPoints
from hairjax._shading._dual_scattering import DENSITY_BACK, dual_tables, dual_terms_batched
from hairjax._shading._marschner_lobes import marschner_lobes
from hairjax._shading._stage import point_colors

TANGENT = np.array([0.0, 0.0, 1.0])
BROWN = 1.3 * np.asarray(EUMELANIN_SIGMA_A) + 0.2 * np.asarray(PHEOMELANIN_SIGMA_A)


_LOBES = jax.jit(jax.vmap(marschner_lobes, in_axes=(None, None, 0, None, None, None)))


def _brute_force_halves(sin_l: float, sigma_a, beta: float, tilt: float = 2.0, ns=800, nphi=128):
    """ā_f, ā_b by a midpoint rule over the sphere of V (s = sin θ_V, φ), NumPy float64,
    of the full lobes R + TT + TRT (π·M·N, so ÷π) with L at inclination asin(sin_l):
    ∫∫ M N cos θ_V dθ_V dφ = ∫∫ M N ds dφ, split at |φ| = π/2."""
    light = jnp.array([np.sqrt(1.0 - sin_l**2), 0.0, sin_l])
    s = -1.0 + (np.arange(ns) + 0.5) * 2.0 / ns
    phi = (np.arange(nphi) + 0.5) * np.pi / nphi  # (0, π); N is even in φ: doubled below
    S, P = np.meshgrid(s, phi, indexing="ij")
    c = np.sqrt(1.0 - S**2)
    eye = np.stack([c * np.cos(P), c * np.sin(P), S], -1).reshape(-1, 3)
    args = (
        jnp.asarray(TANGENT),
        light,
        jnp.asarray(eye),
        jnp.asarray(sigma_a),
        jnp.asarray(beta),
        jnp.asarray(tilt),
    )
    r, tt, trt = (np.asarray(x) for x in _LOBES(*args))
    total = (r[:, None] + tt + trt).reshape(ns, nphi, 3) / np.pi
    cell = (2.0 / ns) * (np.pi / nphi) * 2.0
    forward = (P >= np.pi / 2.0)[..., None]
    return (total * forward).sum((0, 1)) * cell, (total * ~forward).sum((0, 1)) * cell


@pytest.mark.parametrize("beta", [0.05, 0.3])
@pytest.mark.parametrize("sigma_a", [np.zeros(3), BROWN], ids=["white", "brown"])
def test_tables_match_a_brute_force_integration_of_the_lobes(beta, sigma_a):
    tables = dual_tables(jnp.asarray(sigma_a), jnp.asarray(beta), jnp.asarray(2.0))
    grid = np.linspace(-1.0, 1.0, tables.a_f.shape[0])
    for j in (16, 20, 24, 28, 4):  # sin θ = 0, ±0.25 … 0.75
        forward, backward = _brute_force_halves(grid[j], sigma_a, beta)
        # 8 %: the tables take θ_d on the specular cone (θ_d = θ_L) and M's share inside the
        # sphere at its peak; the lobes' N varies with θ_d across M's width (measured up to
        # 7 % in ā_b at β_m = 0.3, sin θ = −0.75; 4 % at β_m = 0.05).
        np.testing.assert_allclose(np.asarray(tables.a_f[j]), forward, rtol=0.08)
        np.testing.assert_allclose(np.asarray(tables.a_b[j]), backward, rtol=0.08)
    # Light perpendicular to the fibre, narrow lobes: the approximation's error vanishes.
    if beta == 0.05:
        forward, backward = _brute_force_halves(0.0, sigma_a, beta)
        np.testing.assert_allclose(np.asarray(tables.a_f[16]), forward, rtol=0.005)
        np.testing.assert_allclose(np.asarray(tables.a_b[16]), backward, rtol=0.005)


def test_without_absorption_forward_and_backward_attenuation_is_the_lobes_albedo():
    """ā_f + ā_b is the lobes' albedo (brute force, all of φ). Karis's approximations are
    not energy conserving: at σ_a = 0 their albedo reaches ~1.1 at oblique light (recorded
    in docs/model.md §19); ā_f < 1 holds, which the back-scatter's series needs."""
    tables = dual_tables(jnp.zeros(3), jnp.asarray(0.3), jnp.asarray(2.0))
    for j in (16, 24, 8):
        albedo = sum(_brute_force_halves(np.linspace(-1, 1, 33)[j], np.zeros(3), 0.3))
        # 5 %: as in the tables' test (the specular-cone θ_d), for the sum.
        np.testing.assert_allclose(np.asarray(tables.a_f[j] + tables.a_b[j]), albedo, rtol=0.05)
    for beta in (0.02, 0.3, 1.0):
        tables = dual_tables(jnp.zeros(3), jnp.asarray(beta), jnp.asarray(2.0))
        assert float(jnp.max(tables.a_f)) < 0.95
        assert float(jnp.max(tables.a_f + tables.a_b)) < 1.15


def _points(n=7, seed=1, omega=None):
    rng = np.random.default_rng(seed)
    unit = lambda x: x / np.linalg.norm(x, axis=1, keepdims=True)  # noqa: E731
    return ShadingPoints(
        tangent=jnp.asarray(unit(rng.normal(size=(n, 3)))),
        to_light=jnp.asarray(unit(rng.normal(size=(n, 3)))),
        to_eye=jnp.asarray(unit(rng.normal(size=(n, 3)))),
        base_color=jnp.ones((n, 3)),
        omega=None if omega is None else jnp.full((n,), omega),
    )


def _gaussian(std, x):
    return np.exp(-0.5 * (x / std) ** 2) / (np.sqrt(2.0 * np.pi) * std)


@pytest.mark.parametrize("omega", [None, 0.0])
def test_with_no_fibre_in_front_dual_adds_the_direct_back_scatter_alone(omega):
    params = MarschnerParams(eumelanin=0.5, longitudinal_roughness=0.25)
    points = _points(omega=omega)
    single = Marschner(params=params).reflectance(points, params)
    dual = Marschner(params=params, multiple_scattering="dual").reflectance(points, params)
    for g in ("weight_r", "weight_tt", "weight_trt"):
        np.testing.assert_array_equal(np.asarray(dual.scattered[g]), 0.0)
    added = sum(np.asarray(dual.lit[g] - single.lit[g]) for g in single.lit)
    # Zinke et al.'s d_b·f_back, f_back = 2·A_b·g(σ_b; x − Δ_b), x = sin θ_L + sin θ_V,
    # from the tables at the point's sin θ_L (linear interpolation, written out here).
    from hairjax._shading import _marschner

    tables = dual_tables(_marschner.absorption(params), params.longitudinal_roughness, params.tilt)
    grid = np.linspace(-1.0, 1.0, tables.a_f.shape[0])
    for p in range(7):
        sin_l = float(points.tangent[p] @ points.to_light[p])
        x = sin_l + float(points.tangent[p] @ points.to_eye[p])
        at = {
            name: np.array(
                [np.interp(sin_l, grid, np.asarray(getattr(tables, name))[:, c]) for c in range(3)]
            )
            for name in ("a_back", "shift_back", "std_back")
        }
        expected = DENSITY_BACK * 2.0 * at["a_back"] * _gaussian(at["std_back"], x - at["shift_back"])
        np.testing.assert_allclose(added[p], expected, rtol=1e-9)
    assert np.all(added > 0)


def test_scattered_light_is_lit_without_tau():
    """The stage: colour = ambient + light·τ·V·Σ w⊙lit + light·V·Σ w⊙scattered."""
    params = MarschnerParams(eumelanin=0.3, longitudinal_roughness=0.3, kappa=0.8, ambient=0.05)
    scene = small_furball_scene(size=12, strands=8).replace(
        shading=Marschner(params=params, multiple_scattering="dual")
    )
    geometry = hj.geometry_stage(scene)
    assert geometry.omega is not None and float(jnp.max(geometry.omega)) > 0.3  # hair in front
    from hairjax._shading._stage import shading_points

    r = scene.shading.reflectance(shading_points(geometry), params)
    tau = np.exp(-0.8 * np.asarray(geometry.omega))[:, None]
    light = np.asarray(geometry.light_rgb)[None, :]
    expected = 0.05 + light * tau * sum(np.asarray(r.lit[g]) for g in r.lit)
    expected = expected + light * sum(np.asarray(r.scattered[g]) for g in r.scattered)
    np.testing.assert_allclose(np.asarray(point_colors(geometry, params)), expected, rtol=1e-12)
    # And the forward-scattered light is there: it brightens the points behind hair.
    assert float(np.max(sum(np.asarray(r.scattered[g]) for g in r.scattered))) > 1e-3


@jax.jit
def _dual_sum(points, eumelanin, beta, kappa):
    params = MarschnerParams(eumelanin=eumelanin, longitudinal_roughness=beta, kappa=kappa)
    r = Marschner(params=params, multiple_scattering="dual").reflectance(points, params)
    return sum(jnp.sum(t) for t in (*r.lit.values(), *r.scattered.values()))


def test_gradients_match_float64_central_differences():
    points, at, eps = _points(omega=3.0), np.array([0.8, 0.3, 0.7]), 1e-5
    grads = jax.grad(_dual_sum, argnums=(1, 2, 3))(points, *at)
    for i, grad in enumerate(grads):
        step = eps * np.eye(3)[i]
        diff = (_dual_sum(points, *(at + step)) - _dual_sum(points, *(at - step))) / (2 * eps)
        # float64 central differences in eumelanin, β_m and κ: truncation O(eps²) and
        # rounding ~1e-16/eps ≈ 1e-11, far below 1e-6 of the value; the tables are
        # piecewise linear in sin θ only (no parameter moves a point across a cell).
        np.testing.assert_allclose(float(grad), float(diff), rtol=1e-6)


@pytest.mark.parametrize("eumelanin", [0.0, 8.0])
@pytest.mark.parametrize("beta", [0.02, 1.0])
@pytest.mark.parametrize("omega", [0.0, 1e3])
def test_finite_values_and_gradients_at_the_extremes(eumelanin, beta, omega):
    points = _points(omega=omega)
    # Grazing: L and V along the fibre at two points, a zero tangent at a third.
    points = ShadingPoints(
        tangent=points.tangent.at[2].set(0.0),
        to_light=points.to_light.at[0].set(points.tangent[0]),
        to_eye=points.to_eye.at[1].set(-points.tangent[1]),
        base_color=points.base_color,
        omega=points.omega,
    )

    value, grads = jax.value_and_grad(_dual_sum, argnums=(1, 2, 3))(points, eumelanin, beta, 0.7)
    assert np.isfinite(float(value)) and all(np.isfinite(float(g)) for g in grads)


def test_dual_terms_are_finite_for_every_grid_corner():
    """Points exactly on the grids' ends (sin θ = ±1, cos φ = ±1) index inside the tables."""
    tables = dual_tables(jnp.asarray(BROWN), jnp.asarray(0.3), jnp.asarray(2.0))
    t = jnp.array([[0.0, 0.0, 1.0]] * 3)
    light = jnp.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]])
    eye = jnp.array([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
    direct, scattered = dual_terms_batched(
        t, light, eye, jnp.ones(3), tables, jnp.asarray(0.3), jnp.asarray(2.0)
    )
    assert np.all(np.isfinite(np.asarray(direct))) and np.all(np.isfinite(np.asarray(scattered)))


def test_scene_file_option(tmp_path):
    path = tmp_path / "scene.toml"
    hair = '[hair]\nsource = "furball"\nstrands = 4\n'
    path.write_text(hair + '[shading]\nmodel = "marschner"\nmultiple_scattering = "dual"\neumelanin = 0.4\n')
    scene = hj.load_scene(path)
    assert scene.shading.multiple_scattering == "dual"
    assert scene.shading.table()["multiple_scattering"] == "dual"
    assert hj.load_scene(path, {"shading.multiple_scattering": "none"}).shading.multiple_scattering == "none"
    path.write_text(hair + '[shading]\nmodel = "marschner"\nmultiple_scattering = "triple"\n')
    with pytest.raises(hj.SceneError, match="multiple_scattering"):
        hj.load_scene(path)
    with pytest.raises(hj.SceneError, match="multiple_scattering"):
        Marschner(multiple_scattering="double")


def test_the_fit_composites_the_scattered_light_as_the_renderer_does():
    params = MarschnerParams(eumelanin=0.3, pheomelanin=0.1, longitudinal_roughness=0.3, kappa=0.8)
    scene = small_furball_scene(size=12, strands=8).replace(
        shading=Marschner(params=params, multiple_scattering="dual")
    )
    image = np.asarray(hj.render(scene))
    names = ("weight_r", "weight_tt", "weight_trt", "eumelanin", "kappa")
    terms = fit_terms(scene, params, names, image)
    from hairjax._fit import _shading_fit

    fitted = np.asarray(_shading_fit.target_image(terms, params)).reshape(image.shape[:2] + (3,))
    # The fit drops fragments hidden below FIT_TRANSMITTANCE_CUTOFF: ≤ that cutoff per pixel.
    np.testing.assert_allclose(fitted, image[..., :3], atol=1e-6)
    # κ reaches every lobe's term inside the model (the scattered light), not through τ only.
    assert {("weight_tt", "kappa"), ("weight_r", "eumelanin")} <= set(terms.pairs)

    def total(plain):
        def f(e, k):
            q = MarschnerParams(eumelanin=e, pheomelanin=0.1, longitudinal_roughness=0.3, kappa=k)
            return jnp.sum(_shading_fit.target_image(terms, q, plain=plain))

        return jax.grad(f, argnums=(0, 1))(0.3, 0.8)

    np.testing.assert_allclose(total(False), total(True), rtol=1e-9)
