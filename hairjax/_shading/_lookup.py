"""Kajiya-Kay from a 2-D lookup table (Heidrich–Seidel, as wenzel-2002 uses it;
docs/model.md §14).

Both Kajiya-Kay intensities depend on T only through L·T and V·T, so they can be
tabulated once on an n × n grid over (u, v) = ((L·T + 1)/2, (V·T + 1)/2) and read back
by bilinear interpolation. The table holds sin(T, L) and max(b, 0)^p; Kd and Ks multiply
what is read (bilinear interpolation is linear, so that equals tabulating Kd·sin and
Ks·b^p). The specular column depends on the shininess p, a fitted parameter, so the
table is built in JAX from `ShadingParams` inside the shading stage: the lookup stays
differentiable in Kd, Ks and p.

Sampling is OpenGL's `texture()` with LINEAR filtering and CLAMP_TO_EDGE on an
`[n, n]` texture (texel (i, j) at column i, row j): texel centres at ((i + ½)/n, (j + ½)/n),
x = u·n − ½, i₀ = ⌊x⌋, weight x − i₀, indices clamped to [0, n − 1]. The GL renderer
uploads this module's table as an RG32F texture and samples it that way.
"""

from __future__ import annotations

from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float

from .._errors import SceneError
from ._kajiya_kay import (
    Cone,
    KajiyaKay,
    ShadingParams,
    kajiya_kay_terms,
    read_kajiya_kay_params,
    seed_cone,
    specular_power,
)
from ._model import Reflectance, ShadingPoints, register_shading_model

__all__ = [
    "KajiyaKayLookup",
    "kajiya_kay_table",
    "bilinear",
    "lookup_coordinates",
    "lookup_terms",
    "kajiya_kay_lookup",
    "LOOKUP_SIZE_RANGE",
]

# The table sizes a scene may ask for: 2 texels already interpolate; 4096² RG32F is 128 MiB.
LOOKUP_SIZE_RANGE = (2, 4096)


def kajiya_kay_table(
    shininess: Float[Array, ""], size: int, cone: Cone = seed_cone
) -> Float[Array, "size size 2"]:
    """The lookup table: `table[j, i] = (sin θ_L, max(b, 0)^p)` at L·T = 2u_i − 1,
    V·T = 2v_j − 1, u_i = (i + ½)/size, v_j = (j + ½)/size (texel centres).

    The entries are `kajiya_kay_terms` of T = z, L = (sin θ_L, 0, cos θ_L),
    V = (sin θ_V, 0, cos θ_V): Kajiya-Kay depends only on the two angles to T (its sines
    are ≥ 0), so these vectors give every point's value, with the same cancellation-free
    gap and guarded power as the analytic model."""
    cos = (jnp.arange(size, dtype=jnp.result_type(float)) + 0.5) / size * 2 - 1
    # |cos| ≤ 1 − 1/size < 1 at texel centres: the sine is positive, never sqrt of < 0.
    sin = jnp.sqrt((1 - cos) * (1 + cos))
    zero = jnp.zeros_like(cos)
    dirs = jnp.stack([sin, zero, cos], axis=1)
    tangent = jnp.array([0.0, 0.0, 1.0], dtype=cos.dtype)

    def entry(to_light, to_eye):
        sin_tl, gap = kajiya_kay_terms(tangent, to_light, to_eye, cone)
        return jnp.stack([sin_tl, specular_power(gap, shininess)])

    # Rows j: V; columns i: L.
    return jax.vmap(jax.vmap(entry, in_axes=(0, None)), in_axes=(None, 0))(dirs, dirs)


def bilinear(table: Float[Array, "n n C"], u: Float[Array, ""], v: Float[Array, ""]) -> Float[Array, " C"]:
    """`table` sampled at (u, v) like GL's `texture()` with LINEAR filtering and
    CLAMP_TO_EDGE: u indexes columns, v rows, texel centres at (k + ½)/n."""
    n = table.shape[0]

    def axis(w):
        x = w * n - 0.5
        k = jnp.floor(x)
        # The clips fire within half a texel of the table's edges (u < ½n or > 1 − ½n):
        # clamp-to-edge, both taps on the edge texel.
        k0 = jnp.clip(k, 0, n - 1).astype(jnp.int32)
        k1 = jnp.clip(k + 1, 0, n - 1).astype(jnp.int32)
        return k0, k1, x - k

    i0, i1, fx = axis(u)
    j0, j1, fy = axis(v)
    top = (1 - fx) * table[j0, i0] + fx * table[j0, i1]
    bottom = (1 - fx) * table[j1, i0] + fx * table[j1, i1]
    return (1 - fy) * top + fy * bottom


def lookup_coordinates(
    tangent: Float[Array, "P 3"],
    to_light: Float[Array, "P 3"],
    to_eye: Float[Array, "P 3"],
) -> tuple[Float[Array, "P 2"], Bool[Array, " P"], Bool[Array, " P"]]:
    """Per point: (u, v) = ((L·T + 1)/2, (V·T + 1)/2), and where the diffuse and the
    specular term may be read from the table at all (geometry only, no parameter)."""
    tl = jnp.sum(tangent * to_light, axis=1)
    tv = jnp.sum(tangent * to_eye, axis=1)

    def nonzero(x):
        return jnp.sum(x * x, axis=1) > 0

    # Fires for zero vectors (a repeated point's tangent, a point light at the point, §1):
    # as in the analytic model, no diffuse without T and L, no highlight without V too.
    # The table alone would read u = ½, where sin θ_L = 1.
    lit = nonzero(tangent) & nonzero(to_light)
    return jnp.stack([0.5 * (1 + tl), 0.5 * (1 + tv)], axis=1), lit, lit & nonzero(to_eye)


def lookup_terms(
    shininess: Float[Array, ""],
    uv: Float[Array, "P 2"],
    lit: Bool[Array, " P"],
    lit_specular: Bool[Array, " P"],
    size: int,
    cone: Cone = seed_cone,
) -> tuple[Float[Array, " P"], Float[Array, " P"]]:
    """(sin θ_L, max(b, 0)^p) per point from the table, built once for all points."""
    table = kajiya_kay_table(shininess, size, cone)
    terms = jax.vmap(bilinear, in_axes=(None, 0, 0))(table, uv[:, 0], uv[:, 1])
    return jnp.where(lit, terms[:, 0], 0.0), jnp.where(lit_specular, terms[:, 1], 0.0)


def kajiya_kay_lookup(
    tangent: Float[Array, "P 3"],
    to_light: Float[Array, "P 3"],
    to_eye: Float[Array, "P 3"],
    params: ShadingParams,
    size: int,
    cone: Cone = seed_cone,
) -> tuple[Float[Array, "P 3"], Float[Array, "P 3"]]:
    """Unshadowed Kajiya-Kay terms at all points from the lookup table (docs/model.md §14).

    Batched over points (the table is built once): (u, v) = ((L·T + 1)/2, (V·T + 1)/2),
    `(sin, spec) = bilinear(table, u, v)`, and the result is `(Kd·sin, Ks·spec)` like
    `kajiya_kay`'s.
    """
    sin_tl, spec = lookup_terms(params.shininess, *lookup_coordinates(tangent, to_light, to_eye), size, cone)
    return sin_tl[:, None] * params.kd[None, :], spec[:, None] * params.ks[None, :]


@register_shading_model
class KajiyaKayLookup(KajiyaKay):
    """The seed's Kajiya-Kay read from a `size` × `size` table (wenzel-2002 after
    Heidrich–Seidel, docs/model.md §14); same parameters as `KajiyaKay`."""

    params: ShadingParams = eqx.field(default_factory=ShadingParams)
    size: int = eqx.field(static=True, default=256)

    name: ClassVar[str] = "kajiya-kay-lookup"
    table_keys: ClassVar[tuple[str, ...]] = (*KajiyaKay.table_keys, "lookup_size")
    gl_id: ClassVar[int | None] = 2

    def __check_init__(self):
        lo, hi = LOOKUP_SIZE_RANGE
        n = self.size
        if isinstance(n, bool) or int(n) != n or not lo <= n <= hi:
            raise SceneError(f"shading.lookup_size must be an integer in [{lo}, {hi}], got {n!r}")

    def reflectance(self, points: ShadingPoints, params: ShadingParams) -> Reflectance:
        sin_tl, spec = lookup_terms(
            params.shininess,
            *lookup_coordinates(points.tangent, points.to_light, points.to_eye),
            int(self.size),
            type(self).cone,
        )
        return Reflectance(
            ambient={"ambient": points.base_color},
            lit={
                "kd": sin_tl[:, None] * points.base_color,
                "ks": jnp.broadcast_to(spec[:, None], points.base_color.shape),
            },
        )

    def gl_table(self, params: ShadingParams):
        return kajiya_kay_table(params.shininess, int(self.size), type(self).cone)

    def table(self) -> dict:
        return {**super().table(), "lookup_size": int(self.size)}

    @classmethod
    def from_table(cls, table) -> KajiyaKayLookup:
        return cls(params=read_kajiya_kay_params(table), **table.given(size=table.integer("lookup_size")))
