"""Streaks along the hair: wenzel-2002's 1-D noise texture (docs/model.md §16).

Each hair i has a texture coordinate u_i; across its ribbon the coordinate runs from u_i
to u_i + Δ (wenzel-2002's "arbitrary value which is constant for all hairs": the bigger Δ,
the thinner the streaks) and it is constant along the hair, so the streaks run along it.
A ribbon here is about a pixel wide and a pixel's box filter covers its whole width (§5),
so a hair's streak factor is the texture's mean over [u_i, u_i + Δ], computed exactly
from the texture's running integral. It multiplies the point's whole colour (wenzel-2002's
"diffuse colour = diffuse intensity · diffuse hair colour · streak colour", and the same
for the specular and, where wenzel-2002 folds it into the intensities, the ambient term).
"""

from __future__ import annotations

import dataclasses

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._errors import SceneError

__all__ = [
    "Streaks",
    "streak_texture",
    "strand_coordinates",
    "streak_prefix",
    "streak_factor",
    "streak_factors",
]


@dataclasses.dataclass(frozen=True)
class Streaks:
    """The streak texture: `texels` values 1 − `contrast`·ξ, ξ uniform in [0, 1) from
    `seed`, repeating with period 1 in u and linearly interpolated between texel centres;
    `width` Δ: the span of u across a hair. Hair coordinates u_i are uniform in [0, 1)
    from the same seed."""

    texels: int = 64
    width: float = 0.05
    contrast: float = 0.6
    seed: int = 0

    def __post_init__(self):
        n = self.texels
        if isinstance(n, bool) or int(n) != n or not 1 <= n <= 65536:
            raise SceneError(f"streaks.texels must be an integer in [1, 65536], got {n!r}")
        if not (np.isfinite(self.width) and 0 < self.width <= 1):
            raise SceneError(f"streaks.width must be in (0, 1], got {self.width!r}")
        if not (np.isfinite(self.contrast) and 0 <= self.contrast <= 1):
            raise SceneError(f"streaks.contrast must be in [0, 1], got {self.contrast!r}")
        if isinstance(self.seed, bool) or int(self.seed) != self.seed or self.seed < 0:
            raise SceneError(f"streaks.seed must be an integer >= 0, got {self.seed!r}")
        for key, cast in (("texels", int), ("width", float), ("contrast", float), ("seed", int)):
            object.__setattr__(self, key, cast(getattr(self, key)))


def streak_texture(streaks: Streaks) -> np.ndarray:
    """The texture's values N_k, `float64[texels]` (texel k centred at u = (k + ½)/texels)."""
    rng = np.random.default_rng(streaks.seed)
    return 1.0 - streaks.contrast * rng.uniform(size=streaks.texels)


def strand_coordinates(streaks: Streaks, num_strands: int) -> np.ndarray:
    """Each hair's coordinate u_i, `float64[S]`, uniform in [0, 1), drawn after the texture."""
    rng = np.random.default_rng(streaks.seed)
    rng.uniform(size=streaks.texels)
    return rng.uniform(size=num_strands)


def streak_prefix(texture: np.ndarray) -> np.ndarray:
    """The running integral at texel centres, in texels: P_0 = 0,
    P_{k+1} = P_k + (N_k + N_{(k+1) mod m})/2, `float64[m + 1]` (P_m: one period)."""
    steps = 0.5 * (texture + np.roll(texture, -1))
    return np.concatenate([[0.0], np.cumsum(steps)])


def _antiderivative(texture, prefix, y):
    """H(y) = ∫₀^y g, g the periodic linear interpolant of `texture` in texel units
    (g(k) = N_{k mod m}): with K = ⌊y⌋, f = y − K, K = q·m + r,
    H = q·P_m + P_r + f·N_r + ½f²(N_{r+1} − N_r)."""
    m = texture.shape[0]
    k = jnp.floor(y)
    f = y - k
    q = jnp.floor(k / m)
    # r = K mod m in [0, m); the clip fires only if float rounding of K/m puts r at m.
    r = jnp.clip(k - q * m, 0, m - 1).astype(jnp.int32)
    n0 = texture[r]
    n1 = texture[(r + 1) % m]
    return q * prefix[m] + prefix[r] + f * n0 + 0.5 * f * f * (n1 - n0)


def streak_factor(
    texture: Float[Array, " m"], prefix: Float[Array, " m1"], u: Float[Array, ""], width: float
) -> Float[Array, ""]:
    """The mean of the streak texture over [u, u + width] (one point; vmap over points):
    (H(b) − H(a))/(width·m), a = u·m − ½, b = (u + width)·m − ½ (texel units)."""
    m = texture.shape[0]
    a = u * m - 0.5
    b = (u + width) * m - 0.5
    return (_antiderivative(texture, prefix, b) - _antiderivative(texture, prefix, a)) / (width * m)


def streak_factors(streaks: Streaks, strand_of_point, num_strands: int, dtype) -> Float[Array, " P"]:
    """§16: each point's streak factor, the texture's mean over its hair's [u_i, u_i + Δ];
    `strand_of_point` `[P]` (NumPy or JAX), `num_strands` the number of hairs S."""
    import jax  # the rest of this module is NumPy and one pure function

    texture = streak_texture(streaks)
    u = jnp.asarray(strand_coordinates(streaks, num_strands), dtype)[strand_of_point]
    return jax.vmap(streak_factor, in_axes=(None, None, 0, None))(
        jnp.asarray(texture, dtype),
        jnp.asarray(streak_prefix(texture), dtype),
        u,
        streaks.width,
    )
