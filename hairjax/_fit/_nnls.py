"""The small non-negative least squares of variable projection (docs/fitting.md,
"Variable projection"): a few gains, c ≥ 0, differentiable in the problem."""

from __future__ import annotations

import itertools

import jax
import jax.numpy as jnp

__all__ = ["nnls"]


@jax.custom_jvp
def nnls(phi: jax.Array, rhs: jax.Array) -> jax.Array:
    """argmin ‖Φc − rhs‖ over c ≥ 0 for a few columns (n ≤ 9: three RGB gains; 2ⁿ
    supports), differentiable in Φ, rhs.

    The optimum is the unconstrained least-squares solution on its own support, and it
    is feasible; every other feasible support solution is a feasible point and costs no
    less. So: solve on all 2ⁿ supports at once, keep the cheapest feasible one (the
    empty support always is), then refine it twice against Φ itself (the normal
    equations alone lose accuracy as cond(Φ)²).

    Its derivative is the least-squares solution's on the chosen support (`_nnls_jvp`),
    not autodiff through the supports' solves and the refinement."""
    return _solve(phi, rhs)[0]


@nnls.defjvp
def _nnls_jvp(primals, tangents):
    """Implicit differentiation on the support s (the normal equations Φₛᵀ(Φₛcₛ − rhs) = 0):

        Φₛᵀ Φₛ dcₛ = Φₛᵀ (drhs − dΦ c) + dΦₛᵀ (rhs − Φ c),   dc = 0 off s,

    solved with the primal's scaled, pinned system. The tangent side is two passes over
    the rows (dΦ c and the two transposed products), where autodiff through the
    refinement had built the 2ⁿ Gram derivatives and a transposed copy of Φ (the fit's
    step spent more time there than in its composite)."""
    phi, rhs = primals
    d_phi, d_rhs = tangents
    c, system, support, scale = _solve(phi, rhs)
    residual = rhs - phi @ c
    # As sums over the rows rather than transposed products: XLA on the CPU then reads
    # each row once, where a dot of Φᵀ with a batch of tangents chose a slow layout.
    u = d_rhs - jnp.sum(d_phi * c[None, :], axis=1)
    g = jnp.sum(phi * u[:, None] + d_phi * residual[:, None], axis=0)
    # Off the support (and on a column pinned dead by scale 0) the pinned rows give dc = 0.
    dc = scale * jnp.linalg.solve(system, jnp.where(support, scale * g, 0.0))
    return c, dc


def _solve(phi: jax.Array, rhs: jax.Array):
    """(c, the scaled system of its support, the support, the column scale): `nnls`'s
    solution and what its derivative reuses."""
    n = phi.shape[1]
    gram, proj = phi.T @ phi, phi.T @ rhs
    diag = jnp.diagonal(gram)
    # Fires for a column that is zero everywhere (a gain with no visible effect, e.g. Ks
    # with the highlight outside every pixel): its coefficient stays 0.
    live = diag > 0
    scale = jnp.where(live, 1.0 / jnp.sqrt(jnp.where(live, diag, 1.0)), 0.0)
    g = gram * jnp.outer(scale, scale)  # unit diagonal on live columns
    h = proj * scale
    supports = jnp.asarray(list(itertools.product((False, True), repeat=n))) & live[None, :]

    def system(support):
        both = support[:, None] & support[None, :]
        # Columns off the support are pinned to 0 by an identity row. A tiny ridge on the
        # support (n·ε of the unit diagonal) fires only when two columns are exactly
        # collinear (e.g. one straight strand, where K_s ∝ K_d): the solve stays finite.
        ridge = n * jnp.finfo(g.dtype).eps
        return jnp.where(both, g, jnp.eye(n, dtype=g.dtype)) + jnp.diag(jnp.where(support, ridge, 0.0))

    def solve(support):
        c = jnp.linalg.solve(system(support), jnp.where(support, h, 0.0))
        cost = 0.5 * c @ g @ c - h @ c
        return c, jnp.where(jnp.all(c >= 0), cost, jnp.inf)

    cs, costs = jax.vmap(solve)(supports)
    best = jnp.argmin(costs)
    support, c = supports[best], cs[best]
    a = system(support)
    for _ in range(2):  # iterative refinement with the residual taken in data space
        r = rhs - phi @ (scale * c)
        c = c + jnp.linalg.solve(a, jnp.where(support, scale * (phi.T @ r), 0.0))
    # Fires when refinement nudges a coefficient at the bound below 0 by rounding.
    return scale * jnp.maximum(c, 0.0), a, support, scale
