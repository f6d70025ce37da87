"""Kajiya-Kay from the lookup table (docs/model.md §14): the table against the formula
written out here in NumPy, GL-style bilinear sampling against hand values, convergence
to the analytic model, gradients against finite differences, and GL against JAX."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import PIXEL_TOL, camera_band, central_difference, refused, small_furball_scene

import hairjax as hj
from hairjax._errors import SceneError
from hairjax._shading._lookup import bilinear, kajiya_kay_table
from hairjax._shading._lookup import kajiya_kay_lookup as _kajiya_kay_lookup

# Compiled once per table size: op-by-op dispatch of the table build is slow.
kajiya_kay_lookup = jax.jit(_kajiya_kay_lookup, static_argnums=(4, 5))


def test_table_holds_sine_and_power_at_texel_centres():
    n, p = 6, 7.5
    table = np.asarray(kajiya_kay_table(jnp.asarray(p), n))
    c = (np.arange(n) + 0.5) / n * 2 - 1  # L·T (columns), V·T (rows)
    s = np.sqrt(1 - c**2)
    base = c[None, :] * c[:, None] + s[None, :] * s[:, None]  # cos(θ_L − θ_V), the seed's b
    np.testing.assert_allclose(table[..., 0], np.broadcast_to(s[None, :], (n, n)), rtol=1e-14)
    np.testing.assert_allclose(table[..., 1], np.maximum(base, 0) ** p, rtol=1e-12, atol=1e-300)


def test_bilinear_is_gl_linear_clamp_to_edge():
    n = 4
    i, j = np.meshgrid(np.arange(n), np.arange(n))
    table = jnp.asarray(np.stack([i, j * j], axis=-1), dtype=float)  # [rows j, columns i]
    sample = lambda u, v: np.asarray(bilinear(table, jnp.asarray(u), jnp.asarray(v)))  # noqa: E731
    # Texel centres return the texel.
    np.testing.assert_array_equal(sample(2.5 / n, 1.5 / n), [2, 1])
    # Between centres: linear weights (column 1.25 → 1.25; rows 1 and 2 → ¾·1 + ¼·4).
    np.testing.assert_allclose(sample(1.75 / n, 1.75 / n), [1.25, 0.75 * 1 + 0.25 * 4], rtol=1e-15)
    # Within half a texel of the edge, and outside [0, 1]: the edge texel.
    np.testing.assert_array_equal(sample(0.0, 1.0), [0, 9])
    np.testing.assert_array_equal(sample(0.1 / n, (n - 0.2) / n), [0, 9])
    np.testing.assert_array_equal(sample(-0.3, 1.7), [0, 9])


def test_lookup_converges_to_the_formula():
    """Bilinear interpolation errs by O(h²) (h = 1/n) where the terms are smooth: away
    from the table's edges (|L·T|, |V·T| < 0.9) the RMSE must fall by ≥ 64 from n = 16 to
    256 (theory 256). At the edges both terms have a square-root singularity (sin θ =
    √(1 − (L·T)²)) and clamp-to-edge holds √(2h) where the formula reaches 0: the error
    there is O(√h) on a band of width O(h), so over all directions the RMSE is O(h) (must
    fall ≥ 8×, theory 16) and the maximum O(√h) (≥ 2×, theory 4)."""
    rng = np.random.default_rng(0)

    def unit(k):
        v = rng.normal(size=(k, 3))
        return jnp.asarray(v / np.linalg.norm(v, axis=1, keepdims=True))

    T, L, V = unit(2000), unit(2000), unit(2000)
    inner = (np.abs(np.sum(T * L, axis=1)) < 0.9) & (np.abs(np.sum(T * V, axis=1)) < 0.9)
    params = hj.ShadingParams(kd=1.0, ks=1.0, shininess=20.0)
    exact = jax.jit(jax.vmap(hj.extend.kajiya_kay, in_axes=(0, 0, 0, None)))(T, L, V, params)
    err = {
        n: [
            np.asarray(a)[:, 0] - np.asarray(e)[:, 0]
            for a, e in zip(kajiya_kay_lookup(T, L, V, params, n), exact)
        ]
        for n in (16, 256)
    }
    for term in range(2):  # diffuse, specular
        coarse, fine = err[16][term], err[256][term]
        rms = lambda d: float(np.sqrt(np.mean(d**2)))  # noqa: E731
        assert rms(fine[inner]) < rms(coarse[inner]) / 64, term
        assert rms(fine) < rms(coarse) / 8, term
        assert np.abs(fine).max() < np.abs(coarse).max() / 2, term
        assert rms(fine) < 3e-3, term  # and an absolute check of the whole path


def test_zero_vectors_get_no_light_as_in_the_formula():
    e = jnp.eye(3)
    zero = jnp.zeros((1, 3))
    params = hj.ShadingParams(kd=1.0, ks=1.0, shininess=2.0)
    d, s = kajiya_kay_lookup(zero, e[:1], e[1:2], params, 8)  # zero tangent
    assert float(jnp.abs(d).max()) == 0 and float(jnp.abs(s).max()) == 0
    d, s = kajiya_kay_lookup(e[:1], zero, e[1:2], params, 8)  # point light at the point
    assert float(jnp.abs(d).max()) == 0 and float(jnp.abs(s).max()) == 0


def lookup_scene(size=32, lookup_size=256, **kw):
    scene = small_furball_scene(strands=60, size=size, **kw)
    return scene.replace(shading=hj.KajiyaKayLookup(scene.params, size=lookup_size))


def test_gradients_in_kd_ks_shininess_match_finite_differences():
    scene = lookup_scene(lookup_size=16)
    geometry = hj.geometry_stage(scene)
    params = scene.params

    @jax.jit
    def loss(p):
        return jnp.sum(hj.shading_stage(geometry, p) ** 2)

    grad = jax.jit(jax.grad(loss))(params)
    for field, index in [("kd", 0), ("ks", 2), ("shininess", ())]:
        leaf = getattr(params, field)

        def f(x, field=field, index=index, leaf=leaf):
            new = leaf.at[index].set(x) if leaf.ndim else jnp.asarray(x)
            return float(loss(eqx.tree_at(lambda m: getattr(m, field), params, new)))

        x = float(leaf[index])
        fd = central_difference(f, x, 1e-6 * max(abs(x), 1.0))
        g = float(getattr(grad, field)[index])
        # Central differences in float64: truncation O(eps²), roundoff ~1e-16·loss/eps.
        assert g == pytest.approx(fd, rel=1e-6, abs=1e-9), field
        assert g != 0, field


def test_scene_checks_lookup_size(tmp_path):
    scene = lookup_scene()
    for bad in (1, 5000, True):
        with pytest.raises(SceneError, match="lookup_size"):
            hj.KajiyaKayLookup(scene.params, size=bad)
    with refused("size", "lookup_size"):  # not an integer
        hj.KajiyaKayLookup(scene.params, size=2.5)
    path = tmp_path / "s.toml"
    path.write_text('[hair]\nsource = "furball"\nstrands = 3\n[shading]\nlookup_size = 32\n')
    with pytest.raises(SceneError, match=r"shading\.lookup_size is not a key of model = 'kajiya-kay'"):
        hj.load_scene(path)
    path.write_text(
        '[hair]\nsource = "furball"\nstrands = 3\n[shading]\nmodel = "kajiya-kay-lookup"\nlookup_size = 32\n'
    )
    loaded = hj.load_scene(path)
    assert loaded.shading == hj.KajiyaKayLookup(loaded.params, size=32)


# --------------------------------------------------------------------------- GL

_SAMPLER = """
#version 450
layout(local_size_x = 64) in;
layout(std430, binding = 0) buffer Coords { vec2 coords[]; };
layout(std430, binding = 1) buffer Values { vec2 values[]; };
uniform sampler2D table;
uniform int count;
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i < uint(count)) values[i] = textureLod(table, coords[i], 0.0).rg;
}
"""


def gl_weight_error(ctx, n: int) -> float:
    """The largest error of this GL's bilinear weights on an n × n LINEAR texture, in
    texels: a table holding its own column and row index returns the texel-space
    coordinate u·n − ½, which is compared with the exact value for 20,000 random (u, v)."""
    import moderngl

    i, j = np.meshgrid(np.arange(n), np.arange(n))
    tex = ctx.texture((n, n), 2, np.stack([i, j], -1).astype("f4").tobytes(), dtype="f4")
    tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
    tex.repeat_x = tex.repeat_y = False
    uv = np.random.default_rng(1).uniform(0.5 / n, 1 - 0.5 / n, (20000, 2)).astype("f4")
    coords, values = ctx.buffer(uv.tobytes()), ctx.buffer(reserve=uv.nbytes)
    comp = ctx.compute_shader(_SAMPLER)
    try:
        coords.bind_to_storage_buffer(0)
        values.bind_to_storage_buffer(1)
        tex.use(0)
        comp["table"] = 0
        comp["count"] = len(uv)
        comp.run(group_x=(len(uv) + 63) // 64)
        ctx.finish()
        out = np.frombuffer(values.read(), "f4").reshape(-1, 2)
        return float(np.abs(out - (uv.astype(np.float64) * n - 0.5)).max())
    finally:
        for obj in (tex, coords, values, comp):
            obj.release()


@pytest.mark.parametrize("n", [8, 100])  # exact and rounded u·n − ½ in GL
def test_gl_lookup_matches_jax(gl, n):
    """GL samples the same table with texture(): the images agree outside the camera band
    (hairjax/_disagreement) to PIXEL_TOL (float32 arithmetic, as for the analytic model) plus
    what GL's bilinear weights may add. That term is measured, not assumed: GPUs often
    keep 8 fractional bits (an error of 2⁻⁹ texel); llvmpipe interpolates in float32,
    measured 0 for n a power of two (u·n − ½ exact), 3.8e-6 texel at n = 100 and 3e-5 at
    n = 1000 (the float32 rounding of u·n − ½). A
    weight error ε moves a bilinear value by ≤ ε·(D_u + D_v), D the largest step between
    neighbouring texels, times Kd or Ks and the light (composite weights sum to ≤ 1)."""
    from hairjax.gl import render_gl

    scene = lookup_scene(size=48, lookup_size=n)
    geometry = hj.geometry_stage(scene)
    jax_image = np.asarray(hj.shading_stage(geometry, scene.params))
    gl_image = render_gl(scene, omega=np.asarray(geometry.omega)).image
    eps = gl_weight_error(gl, n)
    table = np.asarray(kajiya_kay_table(scene.params.shininess, n))
    steps = np.abs(np.diff(table, axis=1)).max(axis=(0, 1)) + np.abs(np.diff(table, axis=0)).max(axis=(0, 1))
    coef = max(float(np.max(scene.params.kd)) * steps[0], float(np.max(scene.params.ks)) * steps[1])
    tol = PIXEL_TOL + eps * coef * max(scene.light.color)
    diff = np.abs(gl_image - jax_image).max(axis=-1).ravel()
    band = camera_band(scene, colour_bound=float(np.max(jax_image[..., :3])))
    bad = np.flatnonzero((diff > tol) & ~band)
    assert bad.size == 0, f"{bad.size} pixels differ by > {tol:.3g}; worst {diff[~band].max():.3g}"
    if n == 8:  # the coarse table does show: the analytic model's image is far from it
        analytic = np.asarray(hj.render(scene.replace(shading=hj.KajiyaKay(scene.params))))
        assert np.abs(analytic - jax_image).max() > 10 * tol


# --------------------------------------------------------------------------- fit

TRUE = hj.ShadingParams(kd=(0.3, 0.5, 0.2), ks=0.4, shininess=25.0, kappa=2.5, ambient=0.05)
INIT = hj.ShadingParams(kd=0.5, ks=0.2, shininess=10.0, kappa=1.0, ambient=0.05)


def test_fit_terms_and_derivatives_for_the_lookup_model():
    """The fit's Kd/Ks images for a lookup scene: its image equals the renderer's (to the
    fit's stated 1e-5 × brightest colour, tests/fit/test_fit.py), and its one-pass derivative
    rule equals forward-mode autodiff of the plain images (as tests/fit/test_fit.py checks for
    the formula; rtol 1e-10: the same maths summed in another order)."""
    from helpers import fit_image, fit_terms

    scene = lookup_scene(size=32, lookup_size=16)
    exact = np.asarray(hj.render(scene, TRUE))[..., :3].reshape(-1, 3)
    names = ("kd", "ks", "shininess", "kappa")
    terms = fit_terms(scene, TRUE, names, exact.reshape(32, 32, 3))
    image = np.asarray(fit_image(terms, TRUE.kd, TRUE.ks, TRUE.shininess, TRUE.kappa, TRUE.ambient))
    assert np.abs(image - exact).max() <= 1e-5 * exact.max()
    analytic = np.asarray(hj.render(scene.replace(shading=hj.KajiyaKay(scene.params)), TRUE))
    assert np.abs(analytic[..., :3].reshape(-1, 3) - exact).max() > 1e-3  # the table shows

    args = (jnp.asarray([0.3, 0.5, 0.2]), jnp.asarray([0.4, 0.4, 0.4]), jnp.asarray(25.0), jnp.asarray(2.5))
    tangent = (
        jnp.asarray([0.1, -0.2, 0.3]),
        jnp.asarray([0.5, 0.1, -0.1]),
        jnp.asarray(3.0),
        jnp.asarray(-0.7),
    )
    _, jvp_f = jax.jvp(lambda *a: fit_image(terms, *a, ambient=TRUE.ambient), args, tangent)
    _, jvp_g = jax.jvp(lambda *a: fit_image(terms, *a, ambient=TRUE.ambient, plain=True), args, tangent)
    np.testing.assert_allclose(jvp_f, jvp_g, rtol=1e-10, atol=1e-13)
    assert np.abs(np.asarray(jvp_g)).max() > 0
