"""Back-to-front "over" compositing as per-fragment weights (docs/model.md §6).

Drawing fragments far to near with over gives, per pixel,

    C = Σ_k α_k c_k T_k + T · C_background,   T_k = Π_{j nearer than k} (1 − α_j),
    T = Π_all (1 − α_j),   alpha channel = 1 − T.

The weights w_k = α_k T_k and T depend on opacity only (geometry stage); the colours c_k on
the shading parameters (shading stage), so C is a weighted sum the shading stage evaluates
without re-compositing.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import jax
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float, Int

if TYPE_CHECKING:
    from ._geometry_stage._stage import Geometry

__all__ = ["segmented_scan", "over_weights", "pixel_weights", "composite", "COMPOSITE_CHUNK"]

# Fragments per step of `composite` and run of `pixel_weights`: their temporaries are a
# few tens of MB at any fragment count (BENCHMARKS.md "Memory").
COMPOSITE_CHUNK = 1 << 20


def segmented_scan(values: Float[Array, " n"], first: Bool[Array, " n"], op) -> Float[Array, " n"]:
    """Inclusive scan of `op` restarting wherever `first` is set."""

    def combine(a, b):
        va, fa = a
        vb, fb = b
        return jnp.where(fb, vb, op(va, vb)), fa | fb

    return jax.lax.associative_scan(combine, (values, first))[0]


def over_weights(
    alpha: Float[Array, " f"], first: Bool[Array, " f"], last: Bool[Array, " f"]
) -> tuple[Float[Array, " f"], Float[Array, " f"]]:
    """Weights w_k = α_k T_k, and each pixel's total transmittance at its last fragment.

    **Arguments:** fragment `alpha`, sorted by pixel and front to back within a pixel;
    `first`/`last` mark each pixel's first and last fragment.

    **Returns:** `(weights, t_total)`; `t_total` is meaningful where `last` is set.
    A product scan, not exp(Σ log(1 − α)): α = 1 stays exact and its gradient finite.
    """
    return _over_run(alpha, first, 1.0)


def _over_run(alpha, first, carry):
    """`over_weights` of a run of fragments whose leading ones (those before its first
    `first`) continue a pixel whose fragments before the run let `carry` through."""
    inclusive = segmented_scan(1.0 - alpha, first, jnp.multiply)
    exclusive = jnp.where(first, 1.0, jnp.concatenate([jnp.ones(1, inclusive.dtype), inclusive[:-1]]))
    # 1 from the run's first `first` on (always, when the run starts a pixel).
    scale = jnp.where(jnp.cumsum(first) == 0, carry, 1.0)
    return alpha * exclusive * scale, inclusive * scale


def pixel_weights(
    alpha: Float[Array, " f"], pixel: Int[Array, " f"], hw: int
) -> tuple[Float[Array, " f"], Float[Array, " hw"]]:
    """(weights w_k = α_k T_k `[F]`, each pixel's transmittance T `[HW]`) of fragments
    sorted by `pixel`, front to back within a pixel (docs/model.md §6); T = 1 where no
    fragment falls.

    The product scan runs over COMPOSITE_CHUNK fragments at a time, each run carrying on
    the transmittance of the pixel the run before it ended in: the scan's temporaries over
    all 55 M fragments of 100k strands at 1024² were 0.93 GiB (BENCHMARKS.md "Memory").
    Only a pixel cut by a run's end sees its product formed in another order (float
    rounding)."""
    n = alpha.shape[0]
    # The runs overwrite every entry of the weights' buffer, which starts as α rather than
    # zeros: a constant of F entries (not computed from an input) is evaluated eagerly
    # under the geometry stage's `ensure_compile_time_eval`, embedded in the compiled
    # program and kept alive by the compilation cache, one per fragment count.
    weights = alpha
    transmittance = jnp.ones(hw, alpha.dtype)
    if n == 0:
        return weights, transmittance

    def run(lo, size, carry, weights, transmittance):
        a, p = (jax.lax.dynamic_slice_in_dim(x, lo, size) for x in (alpha, pixel))
        # The pixels just before and after the run (−1 at either end of all fragments).
        before = jnp.where(lo > 0, pixel[jnp.maximum(lo - 1, 0)], -1)
        after = jnp.where(lo + size < n, pixel[jnp.minimum(lo + size, n - 1)], -1)
        first = p != jnp.concatenate([before[None], p[:-1]])
        last = p != jnp.concatenate([p[1:], after[None]])
        w, inclusive = _over_run(a, first, carry)
        weights = jax.lax.dynamic_update_slice_in_dim(weights, w, lo, 0)
        # Each pixel's last fragment sets its T; the others point past the end, and drop.
        transmittance = transmittance.at[jnp.where(last, p, hw)].set(inclusive, mode="drop")
        return inclusive[-1], weights, transmittance

    full, rest = divmod(n, COMPOSITE_CHUNK)
    state = (jnp.ones((), alpha.dtype), weights, transmittance)
    if full:
        state = jax.lax.fori_loop(0, full, lambda k, s: run(k * COMPOSITE_CHUNK, COMPOSITE_CHUNK, *s), state)
    if rest:
        state = run(full * COMPOSITE_CHUNK, rest, *state)
    return state[1], state[2]


def composite(
    geometry: Geometry, colors: Float[Array, "P C"], *, paired: bool = False
) -> Float[Array, "HW C"]:
    """Σ_k w_k ((1 − t_k) c(p₀) + t_k c(p₁)) per pixel: the hair's part of the composite
    (docs/model.md §6), linear in the point colours. The backdrop term is not included.

    `paired=True` for colours computed in the same XLA program (the shading stage's):
    each point's colour is first laid beside its successor's (`[P, 2C]`) and a fragment
    reads both ends from one row. Without it, XLA on the CPU fuses the per-point shading
    into the per-fragment gathers and evaluates it twice per fragment instead of once per
    point (BENCHMARKS.md "Shading stage"). Colours that are already materialised (the
    fit's stacked gain images) gather directly: the extra table would only cost. The same
    arithmetic either way.

    The fragments are added in steps of COMPOSITE_CHUNK: XLA materialises a scatter's
    `[fragments, C]` operand (and its gradient a `[fragments, 2C]` one), so one step over
    all 55 M fragments of 100k strands at 1024² held 0.67 GiB of temporaries, and its
    gradient 1.6 GiB. Each step is rematerialised in the gradient (`jax.checkpoint`), so
    the gradient keeps no per-step residuals either."""
    hw = geometry.height * geometry.width
    n = geometry.frag_i0.shape[0]
    c = colors.shape[1]
    # The last row's second half wraps to point 0 and is never read: a fragment's i0 is a
    # segment's first point, so i0 + 1 < P.
    table = jnp.concatenate([colors, jnp.roll(colors, -1, axis=0)], axis=1) if paired else colors

    def add(image, lo, size, start):
        """`image` plus fragments [lo, lo + size) — those from `start` on, when given."""
        i0, t, weight, pixel = (
            jax.lax.dynamic_slice_in_dim(x, lo, size)
            for x in (geometry.frag_i0, geometry.frag_t, geometry.frag_weight, geometry.frag_pixel)
        )
        t = t[:, None]
        if paired:
            ends = table[i0]
            c0, c1 = ends[:, :c], ends[:, c:]
        else:
            c0, c1 = table[i0], table[i0 + 1]
        if start is not None:
            # Fires in the last step only, which ends at the last fragment and so starts
            # before `start`: the fragments the step before it added are not added twice.
            weight = jnp.where(lo + jnp.arange(size) >= start, weight, 0.0)
        return image.at[pixel].add(weight[:, None] * ((1 - t) * c0 + t * c1), indices_are_sorted=True)

    image = jnp.zeros((hw, c), colors.dtype)
    if n <= COMPOSITE_CHUNK:
        return add(image, 0, n, None)

    @jax.checkpoint
    def step(k, image):
        start = k * COMPOSITE_CHUNK
        return add(image, jnp.minimum(start, n - COMPOSITE_CHUNK), COMPOSITE_CHUNK, start)

    return jax.lax.fori_loop(0, -(-n // COMPOSITE_CHUNK), step, image)
