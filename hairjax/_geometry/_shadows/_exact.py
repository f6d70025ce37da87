"""`method = "exact"`: the N → ∞ limit of opacity maps (docs/model.md §7): Ω̄(z), the 3 × 3
box average of the summed alpha strictly nearer the light than the point's own depth,
from per-texel prefix sums of the light-space fragments sorted by (texel, depth).
"""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, Int

from ..._composite import segmented_scan
from ..._constants import SHADOW_FILTER_RADIUS
from .._projection import View
from ._base import AbstractShadowMethod, check_resolution, register_shadow_method
from ._frame import ShadowInputs, light_fragments

__all__ = ["ExactShadows", "ExactSetup", "exact_opacity"]


@dataclasses.dataclass(frozen=True)
class ExactSetup:
    """What Ω needs that does not depend on opacity: light-space fragments
    `frag_strand[F]`, `frag_coverage[F]` sorted by (texel, depth) with `frag_first[F]`
    marking each texel's first, and per point `index[P, 9]`, `weight[P, 9]` into the
    per-texel prefix sums."""

    view: View
    frag_strand: np.ndarray
    frag_coverage: np.ndarray
    frag_first: np.ndarray
    index: np.ndarray
    weight: np.ndarray

    @property
    def fragments(self) -> int:
        """How many light fragments it was planned from."""
        return len(self.frag_coverage)


@register_shadow_method
@dataclasses.dataclass(frozen=True)
class ExactShadows(AbstractShadowMethod):
    """Ω at each point's own depth on a `resolution` × `resolution` light raster."""

    resolution: int = 256
    method = "exact"

    def __post_init__(self):
        object.__setattr__(self, "resolution", check_resolution(self.resolution))

    def point_lookups(self) -> int:
        return (2 * SHADOW_FILTER_RADIUS + 1) ** 2  # `index`, `weight`: one per texel of the filter

    def setup(self, inputs: ShadowInputs) -> ExactSetup:
        resolution = self.resolution
        lf = light_fragments(inputs, resolution)
        frags, frame, tx, ty = lf.frags, lf.frame, lf.tx, lf.ty
        depth, seen, zmin, span = frame.depth, frame.seen, frame.zmin, frame.span
        common = dict(frag_strand=np.asarray(lf.frag_strand), frag_coverage=np.asarray(lf.frag_coverage))

        # exact: fragments sorted by one float key, texel + depth fraction / 2.
        def key(texel, z):
            # The clip fires for depths outside [D₀, D_N]: unseen points (masked below), rounding.
            return texel + 0.5 * np.clip((z - zmin) / span, 0.0, 1.0)

        frag_key = key(frags.pixel.astype(np.float64), frags.depths)
        order = np.argsort(frag_key)
        frag_key = frag_key[order]
        first = np.ones(frags.size, np.bool_)
        first[1:] = frags.pixel[order][1:] != frags.pixel[order][:-1]
        r = SHADOW_FILTER_RADIUS
        offs = np.arange(-r, r + 1)
        ox, oy = np.meshgrid(offs, offs)  # all (2r + 1)² offsets
        nx = tx[:, None] + ox.ravel()[None, :]
        ny = ty[:, None] + oy.ravel()[None, :]
        # Fails for neighbours outside the map (points beyond ±80°) and unseen points: weight 0.
        valid = (nx >= 0) & (nx < resolution) & (ny >= 0) & (ny < resolution) & seen[:, None]
        texel = np.where(valid, ny * resolution + nx, 0).astype(np.float64)
        start = np.searchsorted(frag_key, texel, side="left")
        stop = np.searchsorted(frag_key, key(texel, depth[:, None]), side="left")
        # [start, stop): the texel's fragments strictly nearer the light than the point; the
        # per-texel inclusive prefix at stop − 1 sums them.
        has_any = valid & (stop > start)
        common["frag_strand"] = common["frag_strand"][order]
        common["frag_coverage"] = common["frag_coverage"][order]
        return ExactSetup(
            view=frame.view,
            frag_first=first,
            index=np.where(has_any, stop - 1, 0),
            weight=np.where(has_any, 1.0 / (2 * r + 1) ** 2, 0.0),
            **common,
        )

    def omega(self, setup: ExactSetup, alpha):
        dtype = jnp.result_type(float)
        return _exact_opacity(
            alpha,
            setup.frag_strand,
            jnp.asarray(setup.frag_coverage, dtype),
            setup.frag_first,
            setup.index,
            jnp.asarray(setup.weight, dtype),
        )

    def omega_numpy(self, setup: ExactSetup, alpha: np.ndarray) -> np.ndarray:
        """`omega` in NumPy and float64, for precomputed inputs that are not differentiated
        (the Scheuermann model's hair occlusion, docs/model.md §17): `exact_opacity`'s
        per-texel inclusive prefix sums, nearest first, read at each point's (2r + 1)²
        texels. One set-up per light direction, each of its own fragment count: NumPy
        compiles nothing per shape, where the jitted `omega` would compile once per count."""
        frag_alpha = np.asarray(alpha, np.float64)[setup.frag_strand] * setup.frag_coverage
        if frag_alpha.size == 0:  # fires when no segment reaches the raster: Ω = 0
            return np.zeros(setup.index.shape[0])
        cum = np.cumsum(frag_alpha)
        group = np.cumsum(setup.frag_first) - 1
        starts = np.flatnonzero(setup.frag_first)
        prefix = cum - (cum[starts] - frag_alpha[starts])[group]
        return np.sum(setup.weight * prefix[setup.index], axis=1)


@eqx.filter_jit
def _exact_opacity(alpha, frag_strand, frag_coverage, frag_first, index, weight):
    return exact_opacity(alpha[frag_strand] * frag_coverage, frag_first, index, weight)


def exact_opacity(
    frag_alpha: Float[Array, " f"], frag_first, index: Int[Array, "p k"], weight: Float[Array, "p k"]
) -> Float[Array, " p"]:
    """Ω̄(z) at each point's own depth from per-texel prefix sums (N → ∞)."""
    if frag_alpha.shape[0] == 0:  # fires when no segment reaches the light's raster: Ω = 0
        return jnp.zeros(index.shape[0], frag_alpha.dtype)
    prefix = segmented_scan(frag_alpha, frag_first, jnp.add)
    return jnp.sum(weight * prefix[index], axis=1)
