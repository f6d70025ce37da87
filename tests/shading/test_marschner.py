"""The `marschner` model (docs/model.md §19): melanin as Mitsuba defines it, the lobes'
physical properties, the scene file, gradients against float64 central differences and
finite values and gradients at the extremes docs/model.md §19 ("Guards") names (roughness
0.02 and 1, melanin 0 and 8, grazing light and view, back-lit φ = π, L and V along the fibre)."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import central_difference, small_furball_scene

import hairjax as hj
from hairjax._errors import SceneError
from hairjax._shading._marschner import absorption
from hairjax._shading._marschner_lobes import (
    Azimuthal,
    azimuthal_quadrature,
    fresnel_dielectric,
    lobe_widths,
    logistic_scale,
    marschner_lobes,
)

HAIR = '[hair]\nsource = "furball"\nstrands = 20\npoints = 4\n'
T = jnp.array([0.0, 1.0, 0.0])  # the fibre along y: sin θ = y, φ measured in the x-z plane


def direction(theta, phi):
    """A unit vector at longitudinal angle θ (from the normal plane) and azimuth φ."""
    return jnp.array([jnp.cos(theta) * jnp.cos(phi), jnp.sin(theta), jnp.cos(theta) * jnp.sin(phi)])


def lobes(theta_l, phi_l, theta_v, phi_v, sigma=(0.0, 0.0, 0.0), beta=0.3, tilt=2.0, azimuthal=None):
    return marschner_lobes(
        T,
        direction(theta_l, phi_l),
        direction(theta_v, phi_v),
        jnp.asarray(sigma, jnp.float64),
        jnp.asarray(beta, jnp.float64),
        jnp.asarray(tilt, jnp.float64),
        azimuthal,
    )


CHIANG = Azimuthal(jnp.asarray(0.3), 64)


def test_absorption_is_mitsubas_pigment_mapping():
    """σ_a = eumelanin·(0.419, 0.697, 1.37) + pheomelanin·(0.187, 0.4, 1.05) + sigma_a: the
    numbers typed from Mitsuba 3's src/bsdfs/hair.cpp (EUMELANIN_SIGMA_A, PHEOMELANIN_SIGMA_A)."""
    params = hj.MarschnerParams(eumelanin=1.3, pheomelanin=0.2, sigma_a=(0.1, 0.0, 0.2))
    expected = 1.3 * np.array([0.419, 0.697, 1.37]) + 0.2 * np.array([0.187, 0.4, 1.05]) + [0.1, 0.0, 0.2]
    np.testing.assert_allclose(np.asarray(absorption(params)), expected, rtol=1e-15)


def test_lobe_widths_are_chiangs_variances():
    """√v = 0.726β + 0.812β² + 3.7β²⁰ (Mitsuba's update(): m_v[0]), v/4 and 4v for TT, TRT."""
    for beta in (0.02, 0.3, 1.0):
        std = 0.726 * beta + 0.812 * beta**2 + 3.7 * beta**20
        np.testing.assert_allclose(
            np.asarray(lobe_widths(jnp.asarray(beta))), [std, std / 2, 2 * std], rtol=1e-15
        )


def test_fresnel_at_normal_and_grazing_incidence():
    """((η − 1)/(η + 1))² at normal incidence (0.0465 for η = 1.55) and 1 at grazing."""
    np.testing.assert_allclose(float(fresnel_dielectric(jnp.asarray(1.0))), (0.55 / 2.55) ** 2, rtol=1e-14)
    np.testing.assert_allclose(float(fresnel_dielectric(jnp.asarray(0.0))), 1.0, rtol=1e-14)


def test_without_absorption_the_fibre_scatters_about_all_light():
    """∫ Σ_p M_p N_p dω ≈ 1 for σ_a = 0 (Chiang et al. 2016: Σ_p A_p = 1 without absorption).
    Karis's azimuthal distributions are fits: N_TRT's exp(17 cos φ − 16.78) integrates to
    2π I₀(17) e^−16.78 = 0.76 (computed below), not 1, on a lobe carrying < 10 % of the
    light, and h_TT is approximate; so 5 % either way, not equality."""
    from scipy.special import i0e

    assert abs(2 * np.pi * i0e(17.0) * np.exp(17.0 - 16.78) - 0.76) < 0.01
    n = 160
    theta = (np.arange(n) + 0.5) / n * np.pi - np.pi / 2
    phi = (np.arange(2 * n) + 0.5) / (2 * n) * 2 * np.pi - np.pi
    th, ph = np.meshgrid(theta, phi, indexing="ij")
    eyes = np.stack([np.cos(th) * np.cos(ph), np.sin(th), np.cos(th) * np.sin(ph)], -1).reshape(-1, 3)
    weights = (np.cos(th) * (np.pi / n) * (np.pi / n)).ravel()
    for theta_l, azimuthal in ((0.0, None), (0.5, None), (0.5, CHIANG)):
        r, tt, trt = jax.vmap(
            lambda v: marschner_lobes(
                T, direction(theta_l, 0.0), v, jnp.zeros(3), jnp.asarray(0.3), jnp.asarray(2.0)
            )
        )(jnp.asarray(eyes))
        total = (np.asarray(r) + np.asarray(tt)[:, 0] + np.asarray(trt)[:, 0]) / np.pi
        assert 0.95 < float(np.sum(total * weights)) < 1.05


def test_logistic_scale_is_mitsubas():
    """s = √(π/8)(0.265β + 1.194β² + 5.372β²²) (Mitsuba's update(): m_s)."""
    for beta in (0.05, 0.3, 1.0):
        expected = np.sqrt(np.pi / 8) * (0.265 * beta + 1.194 * beta**2 + 5.372 * beta**22)
        np.testing.assert_allclose(float(logistic_scale(jnp.asarray(beta))), expected, rtol=1e-14)


def test_far_field_azimuth_integrates_to_the_mean_attenuation():
    """∫ N_p dφ over [−π, π] = ½ ∫ A_p(h) dh: the trimmed logistic has unit mass on the
    circle, whatever the roughness. A_R = F(cos θ_d cos γ) here by an independent
    Gauss-Legendre rule in h (float64, 200 nodes: converged to 1e-10)."""
    cos_d, eta = 0.9, 1.55
    a = cos_d / np.sqrt(eta**2 - 1 + cos_d**2)
    cos_t = np.sqrt(1 - (1 - cos_d**2) / eta**2)
    x, w = np.polynomial.legendre.leggauss(200)
    mean_r = 0.5 * np.sum(w * np.asarray(fresnel_dielectric(jnp.asarray(cos_d * np.sqrt(1 - x**2)))))
    phis = (np.arange(2000) + 0.5) / 2000 * np.pi  # N_p is even: 2 ∫₀^π
    for beta_n in (0.1, 0.3, 0.8):
        az = Azimuthal(jnp.asarray(beta_n), 512)
        n_r = jax.vmap(
            lambda phi, az=az: azimuthal_quadrature(
                phi, jnp.asarray(cos_d), jnp.asarray(a), jnp.asarray(cos_t), jnp.zeros(3), az
            )[0]
        )(jnp.asarray(phis))
        # midpoint rules: 512 nodes across the fibre, 2000 in φ; 1e-4 of a mean of ~0.06
        np.testing.assert_allclose(2 * float(np.sum(np.asarray(n_r))) * np.pi / 2000, mean_r, rtol=1e-4)


def test_far_field_quadrature_converges():
    """64 nodes across the fibre (the default) against 1024, β_n 0.3 (Mitsuba's default):
    every lobe within 2 % at a front, side and back-lit pair (the bound docs/model.md §19
    states; measured: R at φ = 0, where Φ_R = −2γ sweeps fastest, 1.6 %)."""
    sigma = np.asarray(absorption(hj.MarschnerParams()))
    for phi in (0.0, 1.2, np.pi - 0.1):
        coarse = lobes(0.3, 0.0, -0.25, phi, sigma=sigma, azimuthal=CHIANG)
        fine = lobes(0.3, 0.0, -0.25, phi, sigma=sigma, azimuthal=Azimuthal(jnp.asarray(0.3), 1024))
        for c, f in zip(coarse, fine):
            np.testing.assert_allclose(np.asarray(c), np.asarray(f), rtol=2e-2, atol=1e-6)


def test_tilt_moves_the_r_peak_as_mitsubas_reframe():
    """The R lobe peaks where sin θ_L + sin(θ_V − 2α) = 0 (Mitsuba's reframe of the eye's
    direction for p = 0): θ_V = 2α − θ_L, so a tilt of 3° moves the peak by +6°."""
    theta_l = 0.3
    grid = np.deg2rad(np.linspace(-40.0, 10.0, 2001))
    for tilt in (0.0, 3.0):
        r = jax.vmap(lambda tv: lobes(theta_l, 0.0, tv, 0.0, tilt=tilt, beta=0.1)[0])(jnp.asarray(grid))
        peak = grid[int(np.argmax(np.asarray(r)))]
        # one grid step (0.025°) plus the Gaussian's cos(φ/2)-independent skew, < 0.05°
        assert abs(np.rad2deg(peak) - (2 * tilt - np.rad2deg(theta_l))) < 0.05


def test_transmission_dominates_back_lit_and_melanin_absorbs_it():
    """Back-lit (φ = π, θ_V = −θ_L): TT, the light through the fibre, outshines R (which has
    cos(φ/2) = 0 there); melanin absorbs TT and TRT, blue most (σ_a largest for blue), and
    leaves R alone; without melanin TT and TRT are grey."""
    clear = lobes(0.2, 0.0, -0.2, np.pi)
    dark = lobes(0.2, 0.0, -0.2, np.pi, sigma=np.asarray(absorption(hj.MarschnerParams(eumelanin=1.3))))
    assert float(clear[1][0]) > 100 * float(clear[0])
    np.testing.assert_allclose(np.asarray(clear[1]), float(clear[1][0]), rtol=1e-14)
    assert float(dark[0]) == pytest.approx(float(clear[0]), rel=1e-14)
    assert np.all(np.asarray(dark[1]) < np.asarray(clear[1]))
    assert dark[1][2] < dark[1][1] < dark[1][0]


# --------------------------------------------------------------------------- extremes

GRAZING = [
    # (θ_L, φ_L, θ_V, φ_V): L and V along the fibre (θ = ±90°), opposite (cos θ_d = 0),
    # back-lit φ = π exactly, and grazing within 1e-7 of the poles.
    (np.pi / 2, 0.0, 0.0, 0.0),
    (np.pi / 2, 0.0, -np.pi / 2, 0.0),
    (0.0, 0.0, 0.0, np.pi),
    (0.3, 0.0, -0.3, np.pi),
    (np.pi / 2 - 1e-7, 0.0, -(np.pi / 2 - 1e-7), 1.0),
    (-np.pi / 2, 0.0, np.pi / 2, 0.0),
]
EXTREMES = [dict(beta=b, melanin=m) for b in (0.02, 1.0) for m in (0.0, 8.0)]
AZIMUTHAL_EXTREMES = [None, Azimuthal(jnp.asarray(0.02), 16), Azimuthal(jnp.asarray(1.0), 16)]


# Each pair compiles one vmapped gradient: both precisions for Karis's closed forms, one
# each for the far field at the two ends of β_n.
@pytest.mark.parametrize(
    "dtype, azimuthal",
    [
        (jnp.float64, None),
        (jnp.float32, None),
        (jnp.float64, AZIMUTHAL_EXTREMES[1]),
        (jnp.float32, AZIMUTHAL_EXTREMES[2]),
    ],
    ids=["float64-karis", "float32-karis", "float64-chiang-0.02", "float32-chiang-1"],
)
def test_lobes_and_gradients_are_finite_at_the_extremes(dtype, azimuthal):
    """Every guard of _marschner_lobes fires somewhere in GRAZING × EXTREMES; the lobes and
    their gradients in σ_a, β_m, the tilt and the directions stay finite and ≥ 0."""

    def total(t, light, eye, sigma, beta, tilt):
        return sum(jnp.sum(x) for x in marschner_lobes(t, light, eye, sigma, beta, tilt, azimuthal))

    cases = [(tl, pl, tv, pv, ex) for tl, pl, tv, pv in GRAZING for ex in EXTREMES]
    sigma = jnp.stack(
        [
            absorption(hj.MarschnerParams(eumelanin=ex["melanin"], pheomelanin=ex["melanin"] / 4))
            for *_, ex in cases
        ]
    )
    args = (
        jnp.broadcast_to(T, (len(cases), 3)),
        jnp.stack([direction(tl, pl) for tl, pl, *_ in cases]),
        jnp.stack([direction(tv, pv) for _, _, tv, pv, _ in cases]),
        sigma,
        jnp.asarray([ex["beta"] for *_, ex in cases]),
        jnp.full(len(cases), 2.0),
    )
    args = tuple(x.astype(dtype) for x in args)
    values = jax.jit(jax.vmap(lambda *x: marschner_lobes(*x, azimuthal)))(*args)
    value, grads = jax.jit(jax.vmap(jax.value_and_grad(total, argnums=(1, 2, 3, 4, 5))))(*args)
    for x in values:
        x = np.asarray(x)
        assert np.all(np.isfinite(x)) and np.all(x >= 0), [cases[i] for i in np.flatnonzero(~(x >= 0))]
    assert np.all(np.isfinite(np.asarray(value)))
    for g in grads:
        bad = ~np.isfinite(np.asarray(g)).reshape(len(cases), -1).all(axis=1)
        assert not bad.any(), [cases[i] for i in np.flatnonzero(bad)]


# --------------------------------------------------------------------------- render level


@pytest.fixture(scope="module")
def scene():
    base = small_furball_scene(strands=50, size=20, maps=4, resolution=16)
    params = hj.MarschnerParams(eumelanin=0.8, pheomelanin=0.3, longitudinal_roughness=0.35, ambient=0.02)
    return base.replace(shading=hj.Marschner(params))


# (field, channel): one channel of each RGB field, every scalar.
FIELDS = [
    ("eumelanin", None),
    ("pheomelanin", None),
    ("sigma_a", 2),
    ("longitudinal_roughness", None),
    ("tilt", None),
    ("weight_r", 0),
    ("weight_tt", 1),
    ("weight_trt", 2),
    ("ambient", 0),
    ("kappa", None),
]


def _with(params, field, channel, value):
    old = getattr(params, field)
    new = value if channel is None else old.at[channel].set(value)
    return dataclasses.replace(params, **{field: new})


@pytest.mark.parametrize("azimuthal", ["karis", "chiang"])
def test_image_gradients_match_central_differences(scene, azimuthal):
    """d(Σ image·weights)/d(parameter) by jax.grad against float64 central differences, for
    every parameter of the model (σ_a at 0.05 so its LOG-searched value is interior); the
    azimuthal roughness with the far field, which reads it."""
    scene = scene.replace(shading=hj.Marschner(scene.params, azimuthal=azimuthal, azimuthal_samples=16))
    fields = FIELDS + ([("azimuthal_roughness", None)] if azimuthal == "chiang" else [])
    geometry = hj.geometry_stage(scene)
    weights = jnp.asarray(np.random.default_rng(0).uniform(size=(20, 20, 4)))
    params = dataclasses.replace(scene.params, sigma_a=jnp.full(3, 0.05))

    @jax.jit
    def loss(p):
        return jnp.sum(hj.shading_stage(geometry, p) * weights)

    grads = jax.grad(loss)(params)
    for field, channel in fields:
        x0 = float(getattr(params, field) if channel is None else getattr(params, field)[channel])
        fd = central_difference(
            lambda x: float(loss(_with(params, field, channel, x))), x0, 1e-4 * max(1.0, abs(x0))
        )
        g = np.asarray(getattr(grads, field))
        g = float(g if channel is None else g[channel])
        # central differences at h = 1e-4: truncation h²·f‴/6 ~ 1e-8 relative on this smooth
        # image, rounding eps·|loss|/(h·|g|) ≲ 1e-8 (loss ~ 10², |g| ≳ 1e-3): 1e-5 is ample.
        assert g == pytest.approx(fd, rel=1e-5, abs=1e-9), field


@pytest.mark.parametrize("extreme", EXTREMES, ids=lambda e: f"beta{e['beta']}-melanin{e['melanin']}")
def test_render_is_finite_at_the_extremes(scene, extreme):
    """Whole renders at roughness 0.02 and 1, melanin 0 and 8, with the light grazing the
    view (nearly behind the hair and along the view axis): finite image and gradients."""
    grazing = scene.replace(light=hj.Light(direction=(0.0, -0.05, -1.0)))
    params = hj.MarschnerParams(
        eumelanin=extreme["melanin"],
        pheomelanin=extreme["melanin"] / 4,
        longitudinal_roughness=extreme["beta"],
    )
    for s in (scene, grazing):
        geometry = hj.geometry_stage(s)
        image, grads = jax.value_and_grad(lambda p, g=geometry: jnp.sum(hj.shading_stage(g, p)))(params)
        assert np.all(np.isfinite(np.asarray(image)))
        assert all(np.all(np.isfinite(np.asarray(x))) for x in jax.tree_util.tree_leaves(grads))


# --------------------------------------------------------------------------- scene file


def test_scene_file_reads_and_writes_the_model(tmp_path):
    """[shading] model = "marschner" with its keys; `sigma_a` alone means σ_a alone (the
    pigments 0, as Mitsuba's `sigma_a`); hj.save_scene writes what load_scene reads back."""
    path = tmp_path / "m.toml"
    path.write_text(
        '[hair]\nsource = "furball"\nstrands = 20\npoints = 4\n'
        '[shading]\nmodel = "marschner"\neumelanin = 0.3\nlongitudinal_roughness = 0.2\ntilt = -1.5\n'
        'weight_tt = [1.0, 0.5, 0.5]\nazimuthal = "chiang"\nazimuthal_samples = 32\n'
    )
    scene = hj.load_scene(path)
    assert isinstance(scene.shading, hj.Marschner)
    assert float(scene.params.eumelanin) == 0.3 and float(scene.params.pheomelanin) == 0.2  # default
    assert float(scene.params.tilt) == -1.5
    assert (scene.shading.azimuthal, scene.shading.azimuthal_samples) == ("chiang", 32)
    np.testing.assert_array_equal(np.asarray(scene.params.weight_tt), [1.0, 0.5, 0.5])
    saved = tmp_path / "saved.toml"
    hj.save_scene(scene, saved)
    again = hj.load_scene(saved)
    assert (again.shading.azimuthal, again.shading.azimuthal_samples) == ("chiang", 32)
    for field in dataclasses.fields(scene.params):
        np.testing.assert_array_equal(
            np.asarray(getattr(again.params, field.name)), np.asarray(getattr(scene.params, field.name))
        )

    path.write_text(HAIR + '[shading]\nmodel = "marschner"\nsigma_a = [0.2, 0.3, 0.5]\n')
    sigma = hj.load_scene(path).params
    np.testing.assert_array_equal(np.asarray(absorption(sigma)), [0.2, 0.3, 0.5])


@pytest.mark.parametrize(
    "line, key",
    [
        ("longitudinal_roughness = 0.0", "longitudinal_roughness"),
        ("longitudinal_roughness = 1.5", "longitudinal_roughness"),
        ("eumelanin = -1", "eumelanin"),
        ("sigma_a = [0.1, -0.2, 0.3]", "sigma_a"),
        ("kd = 0.5", "kd"),
        ('azimuthal = "exact"', "azimuthal"),
        ("azimuthal_samples = 1", "azimuthal_samples"),
        ("azimuthal_roughness = 0", "azimuthal_roughness"),
    ],
)
def test_scene_file_refuses_bad_values_naming_the_key(tmp_path, line, key):
    path = tmp_path / "m.toml"
    path.write_text(HAIR + f'[shading]\nmodel = "marschner"\n{line}\n')
    with pytest.raises(SceneError, match=key):
        hj.load_scene(path)
