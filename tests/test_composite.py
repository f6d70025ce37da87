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
    w, inclusive = over_weights(alpha, first, last)
    np.testing.assert_allclose(w, [1.0, 0.0, 0.5, 0.5, 0.0])
    np.testing.assert_allclose(inclusive[jnp.array([1, 4])], [0.0, 0.0])
    g = jax.grad(lambda a: jnp.sum(over_weights(a, first, last)[0] * jnp.arange(5.0)))(alpha)
    assert np.all(np.isfinite(g))
    # d/dα₁ of (w₁·1) with w₁ = α₁(1 − α₀) = 0 at α₀ = 1 → 0; d/dα₀ = 1·0 − α₁·1 = −0.3.
    np.testing.assert_allclose(g[:2], [-0.3, 0.0], atol=1e-15)
