"""The staged renderer end to end (docs/model.md §6, §9, §10)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import central_difference, small_furball_scene

import hairjax as hj
import hairjax._geometry._shadows._frame as frame_mod
import hairjax._geometry_stage._lighting as lighting_mod
import hairjax._geometry_stage._setup as setup_mod
import hairjax._geometry_stage._stage as stage_mod


def stacked_hairs(ordering="bins", front_first=False):
    """Three hairs along x at depths 5, 6, 7 from the eye, all through row 4's centres."""
    alphas = [0.5, 0.25, 0.8]  # front, middle, back
    colors = [(1.0, 0, 0), (0, 1.0, 0), (0, 0, 1.0)]
    zs = [0.0, -1.0, -2.0]
    idx = [0, 1, 2] if front_first else [2, 1, 0]
    xs = np.linspace(-1.0, 1.0, 5)
    strands = [np.stack([xs, np.zeros(5), np.full(5, zs[i])], axis=1) for i in idx]
    hair = hj.Strands(
        np.concatenate(strands),
        np.arange(4) * 5,
        [alphas[i] for i in idx],
        1.0,
        np.repeat([colors[i] for i in idx], 5, axis=0),
    )
    return hj.Scene(
        hair,
        camera=hj.Camera(eye=(0, 0, 5), target=(0, 0, 0), width=16, height=9),
        shading=hj.KajiyaKay(hj.ShadingParams(kd=0.0, ks=0.0, ambient=1.0)),
        shadows=hj.Shadows("none"),
        ordering=hj.Ordering(ordering, 8) if ordering == "bins" else hj.Ordering(ordering),
        background=(0.2, 0.2, 0.2),
    )


def test_three_stacked_hairs_composite_by_hand():
    img = np.asarray(hj.render(stacked_hairs()))
    assert img.shape == (9, 16, 4) and img.dtype == np.float64
    # Back to front: blue (α .8) over grey, green (α .25), red (α .5).
    acc = np.array([0.2, 0.2, 0.2])
    for a, c in [(0.8, (0, 0, 1.0)), (0.25, (0, 1.0, 0)), (0.5, (1.0, 0, 0))]:
        acc = a * np.asarray(c) + (1 - a) * acc
    np.testing.assert_allclose(img[4, 8, :3], acc, rtol=1e-12)
    np.testing.assert_allclose(img[4, 8, 3], 1 - 0.5 * 0.75 * 0.2, rtol=1e-12)
    # Rows away from the hairs show the background with alpha 0.
    np.testing.assert_allclose(img[0, 0], [0.2, 0.2, 0.2, 0.0])


def test_ordering_matters_and_exact_equals_bins_here():
    # Index order draws the front hair first when it is listed first: a different image.
    good = np.asarray(hj.render(stacked_hairs("bins", front_first=True)))
    wrong = np.asarray(hj.render(stacked_hairs("none", front_first=True)))
    exact = np.asarray(hj.render(stacked_hairs("exact", front_first=True)))
    np.testing.assert_allclose(good, exact, rtol=1e-14)
    assert np.abs(good - wrong)[4, 8, :3].max() > 0.1


def test_image_conventions_row_zero_is_top():
    # One hair above the target: it must appear in the upper half of the image.
    hair = hj.Strands.from_list([[[-0.5, 0.6, 0.0], [0.5, 0.6, 0.0]]], alpha=1.0)
    scene = hj.Scene(
        hair,
        camera=hj.Camera(width=32, height=32),
        shadows=hj.Shadows("none"),
        shading=hj.KajiyaKay(hj.ShadingParams(ambient=1.0)),
    )
    alpha = np.asarray(hj.render(scene))[..., 3]
    rows = np.flatnonzero(alpha.max(axis=1) > 0)
    assert rows.size and rows.max() < 16


def loss_fn(scene, target):
    def loss(params, alpha):
        return jnp.sum((hj.render(scene, params, alpha) - target) ** 2)

    return loss


@pytest.mark.parametrize("shadows", ["opacity-maps", "exact"])
def test_gradients_match_finite_differences(shadows):
    scene = small_furball_scene(shadows=shadows)
    target = hj.render(
        scene, hj.ShadingParams(kd=(0.3, 0.5, 0.2), ks=0.1, shininess=8.0, kappa=2.0, ambient=0.05)
    )
    loss = loss_fn(scene, target)
    params, alpha = scene.params, jnp.asarray(scene.strands.alpha)
    g_params, g_alpha = jax.grad(loss, argnums=(0, 1))(params, alpha)

    def along(field, index):
        def f(x):
            leaf = getattr(params, field)
            leaf = leaf.at[index].set(x) if leaf.ndim else jnp.asarray(x)
            return float(loss(eqx_set(params, field, leaf), alpha))

        return f

    for field, index in [("kd", 0), ("kd", 2), ("ks", 1), ("shininess", ()), ("kappa", ())]:
        x = float(getattr(params, field)[index] if index != () else getattr(params, field))
        eps = 1e-6 * max(abs(x), 1.0)
        fd = central_difference(along(field, index), x, eps)
        g = getattr(g_params, field)
        g = float(g[index] if index != () else g)
        # Central differences in float64: truncation O(eps²) and roundoff ~1e-16·loss/eps.
        assert g == pytest.approx(fd, rel=1e-5, abs=1e-8), field
    for j in np.argsort(-np.abs(np.asarray(g_alpha)))[:3]:
        fd = central_difference(lambda x: float(loss(params, alpha.at[j].set(x))), float(alpha[j]), 1e-6)
        assert float(g_alpha[j]) == pytest.approx(fd, rel=1e-5, abs=1e-8)
    assert np.abs(np.asarray(g_alpha)).max() > 0


def eqx_set(module, field, value):
    import equinox as eqx

    return eqx.tree_at(lambda m: getattr(m, field), module, value)


def test_extreme_values_stay_finite():
    # Zero-length segments and repeated points; a strand along the light (T ∥ L); a = 1.
    strands = [
        [[0, 0, 0], [0, 0, 0], [0.3, 0.1, 0], [0.3, 0.1, 0], [0.6, 0.2, 0.1]],
        [[0.2, 1.0, 0.1], [0.2, 0.5, 0.1], [0.2, 0.0, 0.1]],  # along the light direction
        [[-0.5, 0, 0]],  # a one-point strand
    ]
    hair = hj.Strands.from_list(strands, alpha=1.0)
    scene = hj.Scene(
        hair,
        camera=hj.Camera(eye=(0, 0.3, 3), width=24, height=24),
        light=hj.Light(direction=(0, -1, 0)),
        shadows=hj.Shadows("opacity-maps", 8, 16),
    )
    params = hj.ShadingParams(kd=0.5, ks=1.0, shininess=1e4, kappa=1e3)
    img = hj.render(scene, params)
    assert np.all(np.isfinite(np.asarray(img)))
    assert np.asarray(img)[..., 3].max() > 0
    g_params, g_alpha = jax.grad(lambda p, a: jnp.sum(hj.render(scene, p, a) ** 2), argnums=(0, 1))(
        params, jnp.asarray(hair.alpha)
    )
    for leaf in jax.tree_util.tree_leaves((g_params, g_alpha)):
        assert np.all(np.isfinite(np.asarray(leaf)))


def test_geometry_reused_and_unneeded_work_skipped(monkeypatch):
    scene = small_furball_scene(shadows="none")
    calls, opacity_calls = [], []
    original = setup_mod._prepare
    monkeypatch.setattr(setup_mod, "_prepare", lambda s, *rest: calls.append(s) or original(s, *rest))
    # The render's weights: the host loop's on the CPU, JAX's on another device.
    for name in ("composite_weights", "host_weights"):
        original_weights = getattr(stage_mod, name)
        monkeypatch.setattr(
            stage_mod, name, lambda *a, original=original_weights: opacity_calls.append(1) or original(*a)
        )

    def forbidden(*args, **kwargs):
        raise AssertionError("this stage must not run for this scene")

    monkeypatch.setattr(frame_mod, "light_fragments", forbidden)  # every shadow method's set-up
    monkeypatch.setattr(lighting_mod, "occluder_hits", forbidden)
    a = hj.render(scene)
    b = hj.render(scene, hj.ShadingParams(kd=0.1))
    assert len(calls) == 1 and len(opacity_calls) == 1
    assert np.abs(np.asarray(a) - np.asarray(b)).max() > 0
    assert hj.geometry_stage(scene).omega is None


def test_render_is_jittable_in_params():
    scene = small_furball_scene()
    f = jax.jit(lambda p: hj.render(scene, p))
    np.testing.assert_allclose(f(scene.params), hj.render(scene), rtol=1e-12)


def test_occluder_hides_hair_behind_it():
    # Hair behind the sphere (z = −2) is hidden; a hair in front (z = 1.5) is not.
    behind = [[-0.2, 0.0, -2.0], [0.2, 0.0, -2.0]]
    front = [[-0.2, -0.1, 1.5], [0.2, -0.1, 1.5]]
    hair = hj.Strands.from_list([behind, front], alpha=1.0)
    base = dict(
        camera=hj.Camera(eye=(0, 0, 5), width=32, height=32),
        shadows=hj.Shadows("none"),
        shading=hj.KajiyaKay(hj.ShadingParams(kd=0.0, ks=0.0, ambient=1.0)),
    )
    with_sphere = hj.Scene(
        hair, occluder=hj.Occluder(center=(0, 0, 0), radius=1.0, color=(0.0, 0.0, 0.0)), **base
    )
    img = np.asarray(hj.render(with_sphere))
    without = np.asarray(hj.render(hj.Scene(hair, **base)))
    setup = hj.experimental.prepare(with_sphere)
    # Every remaining fragment belongs to the front hair (points 2, 3).
    assert set(np.unique(setup.frag_i0)) == {2}
    # The sphere (black, lit or not) covers the centre: alpha 1, and hair colour only from the front hair.
    assert img[16, 16, 3] == 1.0
    # The hair behind projects onto the row 15/16 boundary, the front hair to y ≈ 17.3
    # (rows 16, 17): row 15 shows the hair behind only without the sphere.
    assert without[15, 16, 0] > 0.4
    assert img[15, 16, 0] == 0.0
    assert img[17, 16, 0] > 0.4


def test_a_given_draw_order_replaces_the_sort():
    """`render(..., order=…)` draws in a given order (kim-2003 §3, Fig. 8: an order reused
    from an earlier view): the scene's own order gives the identical image, another order
    composites in that order, and the scene's cached stages are left alone."""
    scene = small_furball_scene()
    plain = np.asarray(hj.render(scene))
    own = setup_mod.visibility_order(scene)[4]
    np.testing.assert_array_equal(np.asarray(hj.render(scene, order=own)), plain)
    np.testing.assert_array_equal(
        np.asarray(hj.geometry_stage(scene, order=own).frag_weight),
        np.asarray(hj.geometry_stage(scene).frag_weight),
    )
    assert np.abs(np.asarray(hj.render(scene, order=own[::-1])) - plain).max() > 1e-3
    np.testing.assert_array_equal(np.asarray(hj.render(scene)), plain)  # cache untouched

    # Three hairs listed front first, drawn in index order (front first) although the
    # scene sorts by depth: by hand, red (α .5) over grey, then green (.25), then blue (.8).
    scene = stacked_hairs("bins", front_first=True)
    img = np.asarray(hj.render(scene, order=np.arange(len(scene.strands.segments()))))
    acc = np.array([0.2, 0.2, 0.2])
    for a, c in [(0.5, (1.0, 0, 0)), (0.25, (0, 1.0, 0)), (0.8, (0, 0, 1.0))]:
        acc = a * np.asarray(c) + (1 - a) * acc
    np.testing.assert_allclose(img[4, 8, :3], acc, rtol=1e-12)
    # Segments left out of the order are not drawn: only the red hair's (strand 0's 4).
    red_only = np.asarray(hj.render(scene, order=np.arange(4)))
    np.testing.assert_allclose(red_only[4, 8, :3], 0.5 * np.array([1.0, 0, 0]) + 0.5 * 0.2, rtol=1e-12)


def test_a_given_draw_order_is_checked():
    scene = stacked_hairs()
    n = len(scene.strands.segments())
    with pytest.raises(ValueError, match="more than once"):
        hj.render(scene, order=[0, 1, 1])
    with pytest.raises(ValueError, match="outside"):
        hj.render(scene, order=[0, n])
    with pytest.raises(ValueError, match="outside"):
        hj.render(scene, order=[-1])
    with pytest.raises(ValueError, match="1-D"):
        hj.render(scene, order=np.zeros((2, 2), int))
    with pytest.raises(ValueError, match="1-D"):
        hj.render(scene, order=[0.0, 1.0])
