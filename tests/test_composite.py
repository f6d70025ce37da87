"""Over-compositing weights (docs/model.md §6)."""

import jax
import jax.numpy as jnp
import numpy as np

from hairjax._composite import over_weights


def test_three_known_fragments():
    # Front to back: α = 0.5, 0.25, 0.8. T_k = 1, 0.5, 0.375; T = 0.375·0.2 = 0.075.
    alpha = jnp.array([0.5, 0.25, 0.8])
    first = jnp.array([True, False, False])
    last = jnp.array([False, False, True])
    w, inclusive = over_weights(alpha, first, last)
    np.testing.assert_allclose(w, [0.5, 0.125, 0.3], rtol=1e-15)
    np.testing.assert_allclose(inclusive[2], 0.075, rtol=1e-15)
    colors = np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]])
    background = np.array([0.2, 0.2, 0.2])
    c = np.asarray(w) @ colors + 0.075 * background
    # Back-to-front over by hand: blue over bg, then green, then red.
    acc = background
    for a, col in zip([0.8, 0.25, 0.5], colors[::-1]):
        acc = a * col + (1 - a) * acc
    np.testing.assert_allclose(c, acc, rtol=1e-14)


def test_pixels_restart_and_opaque_fragments_have_finite_gradients():
    alpha = jnp.array([1.0, 0.3, 0.5, 1.0, 0.2])
    first = jnp.array([True, False, True, False, False])
    last = jnp.array([False, True, False, False, True])
    # Compiled: the associative scan run op by op costs seconds of dispatch.
    w, inclusive = jax.jit(over_weights)(alpha, first, last)
    np.testing.assert_allclose(w, [1.0, 0.0, 0.5, 0.5, 0.0])
    np.testing.assert_allclose(inclusive[jnp.array([1, 4])], [0.0, 0.0])
    g = jax.jit(jax.grad(lambda a: jnp.sum(over_weights(a, first, last)[0] * jnp.arange(5.0))))(alpha)
    assert np.all(np.isfinite(g))
    # d/dα₁ of (w₁·1) with w₁ = α₁(1 − α₀) = 0 at α₀ = 1 → 0; d/dα₀ = 1·0 − α₁·1 = −0.3.
    np.testing.assert_allclose(g[:2], [-0.3, 0.0], atol=1e-15)


def test_paired_composite_equals_the_two_gathers_by_hand():
    """composite(paired=True) (the shading stage's one-row read of both end colours) gives
    Σ w ((1 − t) c[i0] + t c[i0 + 1]) per pixel, written out here by hand, as the plain
    form does; a fragment on the last segment (i0 = P − 2) reads the last point, not the
    wrapped row. Tolerance: float64 rounding of a three-term sum."""
    import hairjax as hj
    from hairjax._composite import composite

    scene = hj.Scene(
        hj.furball(strands=30, points=5, seed=2),
        camera=hj.Camera(eye=(0.0, 0.0, 3.0), target=(0.0, 0.0, 0.0), width=24, height=24),
    )
    g = hj.geometry_stage(scene)
    p = g.tangent.shape[0]
    colors = jnp.asarray(np.random.default_rng(0).random((p, 3)))
    i0, t, w, pixel = (np.asarray(x) for x in (g.frag_i0, g.frag_t, g.frag_weight, g.frag_pixel))
    c = np.asarray(colors)
    # One row past the image: the bucket's padding (pixel H·W), which the composite drops.
    by_hand = np.zeros((24 * 24 + 1, 3))
    np.add.at(by_hand, pixel, w[:, None] * ((1 - t)[:, None] * c[i0] + t[:, None] * c[i0 + 1]))
    assert i0.max() == p - 2  # the case the wrap must not touch is exercised
    assert pixel.max() == 24 * 24  # and padding
    for paired in (False, True):
        np.testing.assert_allclose(composite(g, colors, paired=paired), by_hand[:-1], rtol=1e-12, atol=1e-14)


def test_composite_in_steps_equals_one_step_with_its_derivatives(monkeypatch):
    """The composite adds its fragments COMPOSITE_CHUNK at a time. With steps of 7 (so that
    steps cut pixels apart and the last step overlaps the one before it), it equals the sum
    written out by hand, and so do its reverse derivative in the colours and the weights and
    its forward derivative (the fit's Jacobians take both). Tolerance: float64 rounding."""
    import equinox as eqx

    import hairjax as hj
    from hairjax import _composite
    from hairjax._composite import composite

    scene = hj.Scene(
        hj.furball(strands=30, points=5, seed=2),
        camera=hj.Camera(eye=(0.0, 0.0, 3.0), target=(0.0, 0.0, 0.0), width=24, height=24),
    )
    g = hj.geometry_stage(scene)
    n, p = g.frag_i0.shape[0], g.tangent.shape[0]
    monkeypatch.setattr(_composite, "COMPOSITE_CHUNK", 7)
    assert n % 7 != 0 and n > 14  # several steps, the last one overlapping
    rng = np.random.default_rng(1)
    colors = jnp.asarray(rng.random((p, 3)))
    probe = jnp.asarray(rng.random((24 * 24, 3)))
    i0, t, w, pixel = (np.asarray(x) for x in (g.frag_i0, g.frag_t, g.frag_weight, g.frag_pixel))
    # The linear map by hand: A[pixel, point] with image = A @ colors; its last row is the
    # bucket's padding (pixel H·W), which the composite drops.
    a = np.zeros((24 * 24 + 1, p))
    np.add.at(a, (pixel, i0), w * (1 - t))
    np.add.at(a, (pixel, i0 + 1), w * t)
    a = a[:-1]
    for paired in (False, True):
        np.testing.assert_allclose(composite(g, colors, paired=paired), a @ colors, rtol=1e-12, atol=1e-14)
        d_colors = jax.grad(lambda c: jnp.sum(composite(g, c, paired=paired) * probe))(colors)
        np.testing.assert_allclose(d_colors, a.T @ probe, rtol=1e-12, atol=1e-14)
        _, tangent = jax.jvp(lambda c: composite(g, c, paired=paired), (colors,), (probe[:p] * 0 + 1,))
        np.testing.assert_allclose(tangent, a @ np.ones((p, 3)), rtol=1e-12, atol=1e-14)

    # In the weights: d/dw_k of Σ probe·image = probe[pixel_k] · ((1 − t_k) c[i0] + t_k c[i0 + 1]).
    def of_weights(weight):
        return jnp.sum(composite(eqx.tree_at(lambda x: x.frag_weight, g, weight), colors) * probe)

    c = np.asarray(colors)
    padded_probe = np.concatenate([np.asarray(probe), np.zeros((1, 3))])  # padding adds to no pixel
    by_hand = np.sum(padded_probe[pixel] * ((1 - t)[:, None] * c[i0] + t[:, None] * c[i0 + 1]), axis=1)
    np.testing.assert_allclose(jax.grad(of_weights)(g.frag_weight), by_hand, rtol=1e-12, atol=1e-14)


def test_pixel_weights_in_runs_equal_one_scan(monkeypatch):
    """pixel_weights scans COMPOSITE_CHUNK fragments at a time, carrying a pixel's
    transmittance from one run into the next. With short runs, over pixels holding 1 to 20
    fragments (so that a pixel spans up to four runs) and opaque fragments among them, its
    weights, transmittances and their derivatives in α equal over_weights' over all
    fragments at once (runs of 6 here). Tolerance: float64 rounding of products formed in
    another order."""
    from hairjax import _composite
    from hairjax._composite import pixel_weights

    rng = np.random.default_rng(3)
    counts = rng.integers(1, 21, size=12)
    hw = 40
    pixels = np.sort(rng.choice(hw, size=counts.size, replace=False))
    pixel = jnp.asarray(np.repeat(pixels, counts), jnp.int32)
    n = int(counts.sum())
    alpha = jnp.asarray(np.where(rng.random(n) < 0.05, 1.0, rng.uniform(0.05, 0.6, n)))
    first = np.ones(n, bool)
    first[1:] = np.asarray(pixel)[1:] != np.asarray(pixel)[:-1]
    last = np.ones(n, bool)
    last[:-1] = first[1:]

    def reference(a):
        w, inclusive = over_weights(a, jnp.asarray(first), jnp.asarray(last))
        return w, jnp.ones(hw, a.dtype).at[jnp.asarray(pixels)].set(inclusive[np.flatnonzero(last)])

    monkeypatch.setattr(_composite, "COMPOSITE_CHUNK", 6)
    assert n % 6 != 0 and counts.max() > 12
    probe_w, probe_t = jnp.asarray(rng.random(n)), jnp.asarray(rng.random(hw))

    def loss(f):
        def value(a):
            w, t = f(a)
            return jnp.sum(w * probe_w) + jnp.sum(t * probe_t)

        return jax.jit(jax.grad(value))

    def tangent(f):
        return jax.jit(lambda a, d: jax.jvp(f, (a,), (d,))[1])

    ours = lambda a: pixel_weights(a, pixel, hw)  # noqa: E731
    # Both sides compiled: the reference's scan run op by op costs 5 s of dispatch.
    for got, want in zip(jax.jit(ours)(alpha), jax.jit(reference)(alpha)):
        np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(loss(ours)(alpha), loss(reference)(alpha), rtol=1e-12, atol=1e-14)
    direction = jnp.asarray(rng.standard_normal(n))
    for got, want in zip(tangent(ours)(alpha, direction), tangent(reference)(alpha, direction)):
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-14)


def test_pixel_weights_leaves_no_fragment_sized_array_behind():
    """The geometry stage runs under `jax.ensure_compile_time_eval`, where an array that
    depends on no input is computed eagerly, embedded in the compiled program and kept by
    the compilation cache. pixel_weights must build no such array of the fragments' size
    (a zeros buffer of 55 M entries held 0.2 GiB per scene at 100k strands / 1024²)."""
    import gc

    from hairjax._composite import pixel_weights

    n = 4099  # a size no other test uses, so that this call compiles afresh
    alpha = jnp.asarray(np.random.default_rng(5).uniform(0.1, 0.5, n))
    pixel = jnp.asarray(np.sort(np.random.default_rng(6).integers(0, 50, n)), jnp.int32)
    stage = jax.jit(pixel_weights, static_argnums=2)  # its cache lives as long as it does
    before = {id(a) for a in jax.live_arrays()}
    with jax.ensure_compile_time_eval():
        out = stage(alpha, pixel, 50)
    assert out[0].shape == (n,)
    del out
    gc.collect()
    left = [a.shape for a in jax.live_arrays() if id(a) not in before and a.size >= n]
    assert left == []
