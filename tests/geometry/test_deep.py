"""Deep opacity maps (docs/model.md §7; Yuksel & Keyser 2008, "Deep Opacity Maps"): Ω by
hand on slabs of parallel hairs, flat and tilted (both lookups), the limits of one wide
layer and of many thin ones, linearity in opacity and the gradients of τ = exp(−κΩ) in
opacity and κ."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import central_difference, small_furball_scene

import hairjax as hj
from hairjax import geometry_stage
from hairjax._geometry._shadows import ShadowInputs, light_fragments

# The slab of tests/geometry/test_shadows.py: light straight down (−y) on three layers of
# hairs along x at y = 0, −0.5, −1, i.e. light depths D₀, D₀ + ½, D₀ + 1 (exact binary
# fractions: every depth difference below is exact). R = 36 texels with a margin of 2 →
# one texel is 0.1; hairs 0.1 apart in z lie on texel edges, so every interior texel gets
# Σ coverage = 1 from each layer. With `split`, the top layer holds only hairs 17 … 32
# (z > 0): there each texel's first hair z₀ is the top layer's depth, on the other side
# the middle layer's.
R, X, SPACING, A = 36, 1.6, 0.1, 0.3
LAYERS = (0.0, -0.5, -1.0)
TOP_FROM = 17


def slab(shadows, alpha=A, split=True):
    zs = -X + SPACING * np.arange(33)
    xs = np.linspace(-X, X, 9)
    strands, layer, hair = [], [], []
    for n, y in enumerate(LAYERS):
        for i, z in enumerate(zs):
            if split and n == 0 and i < TOP_FROM:
                continue
            strands.append(np.stack([xs, np.full(9, y), np.full(9, z)], axis=1))
            layer.append(n)
            hair.append(i)
    scene = hj.Scene(
        hj.Strands.from_list(strands, alpha=alpha),
        camera=hj.Camera(eye=(0, 3, 6), target=(0, -0.5, 0), width=16, height=16),
        light=hj.Light(direction=(0, -1, 0)),
        shading=hj.KajiyaKay(hj.ShadingParams(kd=1.0, ks=0.0, kappa=2.0)),
        shadows=shadows,
    )
    per_point = scene.strands.strand_of_point
    return scene, np.asarray(layer)[per_point], np.asarray(hair)[per_point]


def region_points(layer, hair, side):
    """(layer, point index) of points whose 3 × 3 texels lie where the slab is even: on
    the side with the top layer (`right`, hairs 19 … 29: their box reaches hair 17's
    texels at most) or without it (`left`, hairs 2 … 13), not at a strand's ends."""
    along = np.arange(len(layer)) % 9
    lo, hi = (19, 29) if side == "right" else (2, 13)
    keep = (hair >= lo) & (hair <= hi) & (along >= 1) & (along <= 7)
    return layer[keep], np.flatnonzero(keep)


# Per case: Ω at the top, middle, bottom layer where the top layer is (z₀ = its depth),
# and at the middle and bottom where it is not (z₀ = the middle's), all by hand from
# docs/model.md §7: u = (z − z₀)·K/(KΔ), boundary k holds the alpha with z < z₀ + kΔ.
CASES = [
    # K = 2, Δ = ½ (the default: extent 1 over 2). Top: u = 0 → 0. Middle: u = 1 → boundary
    # 1, the top layer: a. Bottom: u = 2 = K → boundary 2, z < z₀ + 1: 2a. Without the top
    # layer the bottom is at u = 1: boundary 1, the middle layer: a.
    ("deep", 2, 0.0, (0.0, A, 2 * A), (0.0, A)),
    # K = 3, Δ = ⅓: middle u = 1.5, halfway between boundary 1 (a) and 2 (2a); bottom u = 3:
    # 2a. Without the top: bottom u = 1.5, between z < z₀ + ⅓ (a) and z < z₀ + ⅔ (2a).
    ("deep", 3, 0.0, (0.0, 1.5 * A, 2 * A), (0.0, 1.5 * A)),
    # K = 2, Δ = 0.3: middle u = 5/3, ⅔ of the way from boundary 1 (z < z₀ + 0.3: a) to 2
    # (z < z₀ + 0.6: 2a); bottom u = 10/3 > K: beyond the last boundary, the texel's total,
    # its own layer included: 3a. Without the top: bottom u = 5/3 again: 5a/3.
    ("deep", 2, 0.3, (0.0, 5 * A / 3, 3 * A), (0.0, 5 * A / 3)),
    # One layer wider than the hair (Δ = 2 > 1): boundary 1 is the total, Ω = u × total with
    # u = depth behind z₀ / 2: middle ¼ · 3a, bottom ½ · 3a; without the top ¼ · 2a.
    ("deep", 1, 2.0, (0.0, 0.75 * A, 1.5 * A), (0.0, 0.5 * A)),
    # Three layers of Δ = 2: everything lies in the first, so the same as one layer.
    ("deep", 3, 2.0, (0.0, 0.75 * A, 1.5 * A), (0.0, 0.5 * A)),
    # Many thin layers: the middle and bottom sit on boundaries 32 and 64 (32 without the
    # top) and get exactly what lies in front of them, as `exact` does (next case): where a
    # point's 3 × 3 texels share one z₀, the layers are slices of one depth range.
    ("deep", 64, 0.0, (0.0, A, 2 * A), (0.0, A)),
    ("exact", 0, 0.0, (0.0, A, 2 * A), (0.0, A)),
]


@pytest.mark.parametrize("method, layers, spacing, right, left", CASES)
def test_omega_of_a_split_slab_by_hand(method, layers, spacing, right, left):
    shadows = (
        hj.Shadows("deep", layers=layers, resolution=R, layer_spacing=spacing)
        if method == "deep"
        else hj.Shadows("exact", resolution=R)
    )
    scene, layer, hair = slab(shadows)
    omega = np.asarray(geometry_stage(scene).omega)
    for side, expected in (("right", right), ("left", (None, *left))):
        lay, idx = region_points(layer, hair, side)
        assert idx.size > 100 and (side == "right" or np.all(lay > 0))
        # Sums of 9 box-filtered alphas: exact up to float64 rounding.
        np.testing.assert_allclose(omega[idx], np.asarray(expected, float)[lay], rtol=0, atol=1e-12)


# --- the two lookups on a tilted slab ---------------------------------------------------

TILT = 3.0  # light depth per unit z: 0.3 per texel, against the slab's 1 of thickness


def tilted_slab(lookup, layers=4, spacing=0.25):
    """The unsplit slab tilted along z (y = layer − TILT·z): each texel column's first hair
    lies 0.3 deeper than its neighbour's towards −z, three layers ½ apart behind it."""
    zs = -X + SPACING * np.arange(33)
    xs = np.linspace(-X, X, 9)
    strands = [np.stack([xs, np.full(9, y - TILT * z), np.full(9, z)], axis=1) for y in LAYERS for z in zs]
    shadows = hj.Shadows("deep", layers, R, spacing, lookup=lookup)
    return slab(shadows)[0].replace(strands=hj.Strands.from_list(strands, alpha=A), shadows=shadows)


def omega_by_formula(scene, lookup):
    """docs/model.md §7 written out point by point and texel by texel from the light's
    fragments: per texel t the slices j = min(⌊u⌋, K) of its fragments (u from t's own z₀),
    boundary k the alpha of slices < k (k = K + 1: all); a point reads its own u in every
    texel ("layer", 0 where its own texel has no hair) or its u' from each texel's z₀
    ("depth"), k = clamp(⌊u⌋, 0, K − 1), f = clamp(u − k, 0, 1) (k = K, f = 1 beyond K)."""
    sh, s = scene.shadows, scene.strands
    n, r = sh.layers, R
    segs = s.segments()
    lf = light_fragments(ShadowInputs(s.points, segs, s.strand_of_point[segs[:, 0]], s.width, scene.light), r)
    kd = sh.depth_range(lf.frame)
    alpha = s.alpha[lf.frag_strand] * lf.frag_coverage
    pixel, z = lf.frags.pixel, lf.frags.depth
    z0 = {t: z[pixel == t].min() for t in np.unique(pixel)}
    # Per texel its fragments' (slice, alpha).
    held = {t: (np.minimum(np.floor((z[pixel == t] - z0[t]) * n / kd), n), alpha[pixel == t]) for t in z0}

    def value(t, u):
        k = n if u > n else min(max(int(np.floor(u)), 0), n - 1)
        f = 1.0 if u > n else min(max(u - k, 0.0), 1.0)
        slices, a = held[t]
        return (1 - f) * a[slices < k].sum() + f * a[slices < k + 1].sum()

    out = np.zeros(s.num_points)
    for p in range(s.num_points):
        own = lf.ty[p] * r + lf.tx[p]
        if lookup == "layer" and own not in z0:
            continue
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                x, y = lf.tx[p] + dx, lf.ty[p] + dy
                t = y * r + x
                if not (0 <= x < r and 0 <= y < r) or t not in z0:
                    continue
                ref = z0[own] if lookup == "layer" else z0[t]
                out[p] += value(t, (lf.frame.depth[p] - ref) * n / kd) / 9
    return out


def test_both_lookups_on_a_tilted_slab_by_formula():
    """Where neighbours' first hairs differ by 0.3 (more than Δ = 0.25), "layer" compares a
    neighbour's fragments at the point's depth behind the *neighbour's* first hair and
    "depth" at the point's own depth: each matches the formula, and "depth" is the closer
    to `exact` (which counts, in the 9 texels, the alpha strictly in front of the point)."""
    omega = {}
    for lookup in ("layer", "depth"):
        scene = tilted_slab(lookup)
        omega[lookup] = np.asarray(geometry_stage(scene).omega)
        # Sums of the same alphas in another order: float64 rounding only.
        np.testing.assert_allclose(omega[lookup], omega_by_formula(scene, lookup), rtol=0, atol=1e-12)
    exact = np.asarray(
        geometry_stage(tilted_slab("layer").replace(shadows=hj.Shadows("exact", resolution=R))).omega
    )
    assert np.abs(omega["layer"] - omega["depth"]).max() > 0.8 * A  # the lookups do differ here
    # Measured: mean |Ω − Ω_exact| 0.042 ("depth") against 0.084 ("layer"), exact's mean 0.32.
    assert np.abs(omega["depth"] - exact).mean() < 0.6 * np.abs(omega["layer"] - exact).mean()


def test_receivers_in_a_texel_without_hair_outside_the_map_and_beyond_the_last_boundary():
    """Occluder-style receivers (docs/model.md §13) under the whole slab at depth D₀ + 0.8,
    between its middle (D₀ + ½) and bottom (D₀ + 1) layers; K = 2, Δ = 0.3."""
    scene, _, _ = slab(hj.Shadows("deep", 2, R, 0.3, lookup="layer"), split=False)
    s = scene.strands
    receivers = np.array(
        [
            # Beside the slab's end (x = 1.6; texel x ∈ [1.6, 1.7), z ∈ [0.5, 0.6)): no
            # fragment reaches the texel (ribbons end at s = L), its x-neighbours hold the
            # whole slab.
            [1.65, -0.8, 0.55],
            [10.0, -0.8, 0.55],  # outside the map
            [0.05, -0.8, 0.55],  # in the slab's interior: u = 0.8/0.3 > K
        ]
    )
    segs = s.segments()
    inputs = ShadowInputs(s.points, segs, s.strand_of_point[segs[:, 0]], s.width, scene.light, receivers)
    alpha = jnp.asarray(s.alpha)
    deep = np.asarray(scene.shadows.omega(scene.shadows.setup(inputs), alpha))
    exact_method = hj.Shadows("exact", resolution=R)
    exact = np.asarray(exact_method.omega(exact_method.setup(inputs), alpha))
    # `exact` counts the two layers in front. Beside the end it filters them in the 3
    # texels of the x-neighbour column, 3 · 2a / 9; deep maps give 0 where the point's own
    # texel has no z₀. Outside: 0 for both. In the interior the point lies beyond the last
    # boundary (z₀ + 0.6) and gets the texel's total, the bottom layer behind it included: 3a.
    np.testing.assert_allclose(exact[-3:], [2 * A / 3, 0.0, 2 * A], atol=1e-12)
    np.testing.assert_allclose(deep[-3:], [0.0, 0.0, 3 * A], atol=1e-12)


@pytest.mark.parametrize("lookup", ["layer", "depth"])
def test_omega_is_linear_in_opacity(lookup):
    a = geometry_stage(slab(hj.Shadows("deep", 3, R, 0.2, lookup), alpha=0.2)[0]).omega
    b = geometry_stage(slab(hj.Shadows("deep", 3, R, 0.2, lookup), alpha=0.4)[0]).omega
    np.testing.assert_allclose(2 * np.asarray(a), np.asarray(b), rtol=1e-12, atol=1e-15)


# --- many thin layers -----------------------------------------------------------------


def ball(shadows):
    return hj.Scene(
        hj.furball(300, 8, seed=1, alpha=0.5),
        light=hj.Light(direction=(0.3, -1, 0.2)),
        camera=hj.Camera(width=8, height=8),
        shadows=shadows,
    )


def layer_limit(scene, layers):
    """By hand in NumPy from the light's fragments (the shared light view, docs/model.md §7):
    per strand point Ω_∞, the K → ∞ limit of deep maps, (1/9) Σ over the 3 × 3 texels t' of
    the alpha with z − z₀(t') < z_p − z₀(t_p) (0 where t_p holds no hair); whether t_p holds
    hair; `offset`, the alpha on which Ω_∞ and `exact`'s [z < z_p] disagree (0 where the 9
    texels share one z₀; all of exact's Ω where t_p holds none); and per K in `layers`
    `inside`, the alpha of the fragments in the point's own layer k, which the
    interpolation weighs by f instead of 0 or 1: |Ω_K − Ω_∞| ≤ inside; and `inside_depth`,
    the same for `lookup = "depth"`: (1/9) Σ_{t'} the alpha of t' in the point's layer k'
    behind z₀(t'), which bounds |Ω_K − Ω_exact| there (its limit is `exact`)."""
    s = scene.strands
    segs = s.segments()
    inputs = ShadowInputs(s.points, segs, s.strand_of_point[segs[:, 0]], s.width, scene.light)
    lf = light_fragments(inputs, 32)
    alpha = s.alpha[lf.frag_strand] * lf.frag_coverage
    pixel, z = lf.frags.pixel, lf.frags.depth
    z0 = np.full(32 * 32, np.inf)
    np.minimum.at(z0, pixel, z)  # each texel's nearest fragment
    span = lf.frame.span  # the default KΔ: D_N − D₀
    n = s.num_points
    zp, tx, ty = lf.frame.depth[:n], lf.tx[:n], lf.ty[:n]
    own = np.where(lf.inside[:n], ty * 32 + tx, 0)
    hair = lf.inside[:n] & np.isfinite(z0[own])
    dp = np.where(hair, zp - z0[own], 0.0)
    # Each texel's fragments as a padded row (depth +∞, alpha 0), and one empty row (R²)
    # for texels outside the map.
    order = np.argsort(pixel, kind="stable")
    counts = np.bincount(pixel, minlength=32 * 32)
    slot = np.arange(len(pixel)) - np.repeat(np.cumsum(counts) - counts, counts)
    depth_rows = np.full((32 * 32 + 1, counts.max()), np.inf)
    alpha_rows = np.zeros((32 * 32 + 1, counts.max()))
    depth_rows[pixel[order], slot] = z[order]
    alpha_rows[pixel[order], slot] = alpha[order] / 9
    first = np.append(np.where(np.isfinite(z0), z0, 0.0), 0.0)  # any finite value where no hair
    limit, offset = np.zeros(n), np.zeros(n)
    inside = {k: np.zeros(n) for k in layers}
    inside_depth = {k: np.zeros(n) for k in layers}
    for oy in (-1, 0, 1):
        for ox in (-1, 0, 1):
            x, y = tx + ox, ty + oy
            there = np.where((x >= 0) & (x < 32) & (y >= 0) & (y < 32), y * 32 + x, 32 * 32)
            behind_first = depth_rows[there] - first[there][:, None]  # [P, M]: t''s fragments
            weight = alpha_rows[there]
            behind = behind_first < dp[:, None]
            limit += np.sum(weight * behind, axis=1)
            offset += np.sum(weight * (behind != (depth_rows[there] < zp[:, None])), axis=1)
            for k in layers:
                own_layer = np.clip(np.floor(dp * k / span), 0, k - 1)
                inside[k] += np.sum(
                    weight * (np.floor(behind_first * k / span) == own_layer[:, None]), axis=1
                )
                # Texels without hair or outside the map have empty rows: any layer, weight 0.
                its_layer = np.clip(np.floor((zp - first[there]) * k / span), 0, k - 1)
                inside_depth[k] += np.sum(
                    weight * (np.floor(behind_first * k / span) == its_layer[:, None]), axis=1
                )
    inside = {k: np.where(hair, v, 0.0) for k, v in inside.items()}
    return limit, hair, offset, inside, inside_depth


def test_many_thin_layers_approach_their_limit_and_exact_within_the_z0_offsets():
    """lookup "layer": |Ω_K − Ω_∞| ≤ the alpha in the point's own layer (it shrinks as K grows); Ω_∞ differs
    from `exact` only by the fragments the per-texel offsets z₀(t') − z₀(t_p) move across
    the point's depth (docs/model.md §7: deep maps are not `exact` in the limit where a
    point's 3 × 3 texels start at different depths)."""
    exact = np.asarray(geometry_stage(ball(hj.Shadows("exact", resolution=32))).omega)
    layers = (4, 64, 1024)
    limit, hair, offset, inside, _ = layer_limit(ball(hj.Shadows("none")), layers)
    errors = []
    for k in layers:
        omega = np.asarray(geometry_stage(ball(hj.Shadows("deep", k, 32, lookup="layer"))).omega)
        # The bounds are sums of the same alphas: float64 rounding only.
        assert np.all(np.abs(omega - limit) <= inside[k] + 1e-9)
        assert np.all(np.abs(omega - exact) <= inside[k] + offset + 1e-9)
        np.testing.assert_array_equal(omega[~hair], 0.0)
        errors.append(np.abs(omega - limit).mean())
    assert errors[0] > errors[1] > errors[2] and errors[2] < 0.05 * errors[0]
    assert np.mean(offset) > 0.1 * np.mean(exact)  # this sparse ball's z₀ does differ


def test_the_depth_lookups_many_layer_limit_is_exact():
    """lookup "depth" reads each texel t' at the point's own depth behind z₀(t'), so as K
    grows (KΔ the hair's extent) Ω → `exact`'s Ω: |Ω_K − Ω_exact| ≤ the alpha of each t' in
    the point's layer k' there, which the interpolation weighs by f' instead of 0 or 1
    (docs/model.md §7), on the sparse ball whose z₀ jumps from texel to texel."""
    exact = np.asarray(geometry_stage(ball(hj.Shadows("exact", resolution=32))).omega)
    layers = (4, 64, 1024)
    *_, inside = layer_limit(ball(hj.Shadows("none")), layers)
    errors = []
    for k in layers:
        omega = np.asarray(geometry_stage(ball(hj.Shadows("deep", k, 32, lookup="depth"))).omega)
        # The bound is a sum of the same alphas: float64 rounding only.
        assert np.all(np.abs(omega - exact) <= inside[k] + 1e-9)
        errors.append(np.abs(omega - exact).mean())
    # Measured: 0.82, 0.074, 0.011 against exact's mean Ω 5.1 (the "layer" lookup stays at 2.0).
    assert errors[0] > errors[1] > errors[2] and errors[2] < 0.005 * np.mean(exact)


# --- gradients ------------------------------------------------------------------------


@pytest.mark.parametrize("lookup", ["layer", "depth"])
def test_transmittance_gradients_in_kappa_and_opacity_match_finite_differences(lookup):
    """Σ_p w_p·τ_p with τ = exp(−κΩ(α)) (docs/model.md §7) through the method's own Ω,
    differentiated in κ and in each strand's opacity α (the image reaches both only through
    τ; the shading and composite after it are the other methods' and tested with them)."""
    scene = small_furball_scene(strands=80, size=16, shadows="deep", resolution=32)
    scene = scene.replace(shadows=dataclasses.replace(scene.shadows, lookup=lookup))
    plan = hj.experimental.prepare(scene).shadow
    weights = jnp.asarray(np.random.default_rng(0).uniform(size=scene.strands.num_points))

    def loss(kappa, alpha):
        return jnp.sum(weights * jnp.exp(-kappa * scene.shadows.omega(plan, alpha)))

    kappa, alpha = 0.8, jnp.asarray(scene.strands.alpha)
    g_kappa, g_alpha = jax.grad(loss, argnums=(0, 1))(kappa, alpha)
    # Central differences in float64: truncation O(eps²) and roundoff ~1e-16·loss/eps.
    fd = central_difference(lambda x: float(loss(x, alpha)), kappa, 1e-6)
    assert float(g_kappa) == pytest.approx(fd, rel=1e-6) and float(g_kappa) < 0
    for j in np.argsort(-np.abs(np.asarray(g_alpha)))[:5]:
        fd = central_difference(lambda x: float(loss(kappa, alpha.at[j].set(x))), float(alpha[j]), 1e-6)
        assert float(g_alpha[j]) == pytest.approx(fd, rel=1e-6)
    assert np.abs(np.asarray(g_alpha)).max() > 0
