"""Safe vector helpers shared by the maths modules."""

from __future__ import annotations

import jax.numpy as jnp
from jaxtyping import Array, Float

from ._constants import SAFE_NORM_EPS


def safe_norm(x: Float[Array, "... 3"]) -> Float[Array, ...]:
    """‖x‖ with a zero (not NaN) gradient at x = 0."""
    sq = jnp.sum(x * x, axis=-1)
    # Double-where: fires for zero vectors (zero-length segments, T ∥ L in ‖T × L‖), where
    # d√s/ds = ∞ would otherwise turn into NaN in the backward pass.
    nonzero = sq > SAFE_NORM_EPS**2
    return jnp.where(nonzero, jnp.sqrt(jnp.where(nonzero, sq, 1.0)), 0.0)


def safe_normalize(x: Float[Array, "... 3"]) -> Float[Array, "... 3"]:
    """x / ‖x‖, and 0 for x = 0 (a direction that does not exist contributes nothing)."""
    n = safe_norm(x)
    # Fires for zero vectors only: divide by 1 instead of 0 and return the zero vector.
    return x / jnp.where(n > 0, n, 1.0)[..., None]
