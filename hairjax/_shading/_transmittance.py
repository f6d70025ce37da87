"""τ = exp(−κΩ): the light reaching a point through hair of opacity Ω (kim-2003 §4,
docs/model.md §7). One definition for the shading stage, the occluder and the fit; the
GL renderer's twin is `transmittance` in hairjax/gl/shaders/model.glsl."""

from __future__ import annotations

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

__all__ = ["transmittance"]


def transmittance(kappa: ArrayLike, omega: Float[ArrayLike, "*shape"]) -> Float[Array, "*shape"]:
    """exp(−κΩ) elementwise (κ ≥ 0, Ω ≥ 0: in (0, 1], no guard needed)."""
    return jnp.exp(-(kappa * jnp.asarray(omega)))
