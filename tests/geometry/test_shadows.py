"""Opacity shadow maps on a slab of parallel hairs, computed by hand (docs/model.md §7)."""

import numpy as np
import pytest
from helpers import shadow_method

import hairjax as hj
from hairjax import geometry_stage
from hairjax._geometry._shadows import map_margin
from hairjax._shading import point_colors

# Light travels straight down (−y). Three layers of hairs along x at y = 0, −0.5, −1.
# The map: R = 36 texels, margin 2 (width 1) → 32 usable texels over the slab's 3.2 units,
# so one texel is 0.1. Hairs 0.1 apart in z give every interior texel Σ coverage = 1 per
# layer (a hair on a texel boundary covers ½ of both texels next to it).
R, X, SPACING, LAYERS, A = 36, 1.6, 0.1, (0.0, -0.5, -1.0), 0.3


def slab(method, maps=3, alpha=A):
    zs = -X + SPACING * np.arange(33)
    xs = np.linspace(-X, X, 9)
    strands = [np.stack([xs, np.full(9, y), np.full(9, z)], axis=1) for y in LAYERS for z in zs]
    hair = hj.Strands.from_list(strands, alpha=alpha)
    return hj.Scene(
        hair,
        camera=hj.Camera(eye=(0, 3, 6), target=(0, -0.5, 0), width=16, height=16),
        light=hj.Light(direction=(0, -1, 0)),
        shading=hj.KajiyaKay(hj.ShadingParams(kd=1.0, ks=0.0, kappa=2.0)),
        shadows=shadow_method(method, maps, R),
    )


def interior_points(scene):
    """(layer, point index) of points whose 3 × 3 box lies inside the evenly covered area."""
    pts = scene.strands.points
    k = np.arange(len(pts)) // 9 % 33  # hair index within its layer
    m = np.arange(len(pts)) % 9  # point index along the hair
    layer = np.arange(len(pts)) // (9 * 33)
    keep = (k >= 2) & (k <= 29) & (m >= 1) & (m <= 7)
    return layer[keep], np.flatnonzero(keep)


def test_map_framing_is_what_the_test_assumes():
    assert map_margin(np.ones(1)) == 2
    setup = hj.experimental.prepare(slab("exact"))
    assert setup.shadow.view.focal == pytest.approx((R - 4) / (2 * X))


@pytest.mark.parametrize(
    "method, maps, expected",
    [
        ("exact", 3, (0.0, A, 2 * A)),
        # N = 2: the middle layer sits on plane 1, the bottom on plane 2.
        ("opacity-maps", 2, (0.0, A, 2 * A)),
        # N = 3: the middle layer is halfway between planes 1 (Ω = a) and 2 (Ω = 2a).
        ("opacity-maps", 3, (0.0, 1.5 * A, 2 * A)),
        # N = 1: linear between Ω(D₀) = 0 and Ω(D₁) = 2a.
        ("opacity-maps", 1, (0.0, A, 2 * A)),
    ],
)
def test_omega_and_transmittance_of_a_slab(method, maps, expected):
    scene = slab(method, maps)
    geom = geometry_stage(scene)
    layer, idx = interior_points(scene)
    omega = np.asarray(geom.omega)[idx]
    # Sums of 9 box-filtered alphas: exact up to float64 rounding.
    np.testing.assert_allclose(omega, np.asarray(expected)[layer], atol=1e-12)
    # Diffuse only, T ⊥ L (sin = 1): colour = Kd·τ = exp(−κΩ).
    colors = np.asarray(point_colors(geom, scene.params))[idx]
    np.testing.assert_allclose(colors[:, 0], np.exp(-2.0 * np.asarray(expected)[layer]), rtol=1e-12)


def test_shadow_none_gives_unit_transmittance():
    scene = slab("none")
    geom = geometry_stage(scene)
    assert geom.omega is None
    _, idx = interior_points(scene)
    np.testing.assert_allclose(np.asarray(point_colors(geom, scene.params))[idx], 1.0, rtol=1e-12)


def test_omega_is_linear_in_opacity():
    a, b = geometry_stage(slab("opacity-maps", 4, 0.2)), geometry_stage(slab("opacity-maps", 4, 0.4))
    np.testing.assert_allclose(2 * np.asarray(a.omega), np.asarray(b.omega), rtol=1e-12, atol=1e-15)


def test_more_maps_converge_to_exact():
    scene = hj.Scene(
        hj.furball(300, 8, seed=1),
        light=hj.Light(direction=(0.3, -1, 0.2)),
        camera=hj.Camera(width=8, height=8),
    )
    exact = np.asarray(geometry_stage(scene.replace(shadows=hj.Shadows("exact", resolution=64))).omega)
    errors = [
        np.abs(
            np.asarray(geometry_stage(scene.replace(shadows=hj.Shadows("opacity-maps", n, 64))).omega) - exact
        ).mean()
        for n in (2, 16, 128)
    ]
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < 0.1 * errors[0]


@pytest.mark.parametrize("pieces", [1, 3], ids=["one piece", "three pieces"])
@pytest.mark.parametrize("x64", [False, True], ids=["float32", "float64"])
def test_a_renders_plan_sums_the_fragments_as_jax_does(x64, pieces, monkeypatch):
    """A render's set-up plans Ω for the scene's own opacities (`ShadowInputs.opacity`):
    opacity maps then sum each cell's fragment alpha on the host and keep no fragments.
    Ω equals the fragment plan's, which JAX sums, bit for bit: with the alpha texture's
    factor (§17), an occluder's receivers (§13) and a point light; with the light's
    raster in one piece and in three, which the host sums piece after piece. A traced α
    still gets the fragment plan, and reversing the host's order of additions changes Ω."""
    import jax
    import jax.numpy as jnp
    from helpers import scheuermann_scene, small_furball_scene

    from hairjax._geometry import _raster
    from hairjax._geometry._shadows import ShadowInputs, light_fragments
    from hairjax._geometry_stage._setup import prepare, render_cutoff

    monkeypatch.setattr(_raster, "PARALLEL_MIN", 0)  # every raster in `pieces` pieces
    monkeypatch.setattr(_raster, "host_threads", lambda: pieces)
    with jax.enable_x64(x64):
        furball = small_furball_scene(strands=80, size=32, maps=16, resolution=32, alpha=0.45)
        scenes = [
            furball,
            furball.replace(
                light=hj.Light(kind="point", position=(1.5, 2.0, 1.0)),
                occluder=hj.Occluder(center=(0.0, 0.0, 0.0), radius=0.3),
            ),
            scheuermann_scene(size=32, strands=60, alpha_texture=(1.0, 0.7, 0.35)),
        ]
        hair = furball.strands
        segments = hair.segments()
        inputs = ShadowInputs(
            hair.points, segments, hair.strand_of_point[segments[:, 0]], hair.width, furball.light
        )
        assert len(light_fragments(inputs, 32).pieces) == pieces
        for scene in scenes:
            summed, full = prepare(scene, cutoff=render_cutoff()).shadow, prepare(scene).shadow
            assert summed.frag_cell is None and summed.slices is not None and full.slices is None
            assert summed.fragments == full.fragments > 500
            alpha = jnp.asarray(scene.strands.alpha, jnp.result_type(float))
            omega = np.asarray(scene.shadows.omega(summed, alpha))
            np.testing.assert_array_equal(omega, np.asarray(scene.shadows.omega(full, alpha)))
            np.testing.assert_array_equal(
                omega[: scene.strands.num_points], np.asarray(geometry_stage(scene).omega)
            )
        # NumPy's unbuffered np.add.at, in fragment order, gives the same sums; reversed, not.
        dtype = summed.slices.dtype
        frag_alpha = np.asarray(alpha)[full.frag_strand] * np.asarray(full.frag_coverage).astype(dtype)
        forward, backward = np.zeros_like(summed.slices), np.zeros_like(summed.slices)
        np.add.at(forward, full.frag_cell, frag_alpha)
        np.add.at(backward, full.frag_cell[::-1], frag_alpha[::-1])
        np.testing.assert_array_equal(forward, summed.slices)
        assert not np.array_equal(backward, summed.slices)
        # A traced α gets the fragment plan: Ω has a gradient in it.
        grad = jax.grad(lambda a: geometry_stage(scene, a).omega.sum())(alpha)
        assert np.all(np.isfinite(grad)) and np.abs(grad).max() > 0
