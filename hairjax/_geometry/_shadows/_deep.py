"""`method = "deep"`: deep opacity maps (Yuksel & Keyser 2008, "Deep Opacity Maps";
docs/model.md §7).

Opacity maps whose slices follow the hair's lit surface instead of fixed planes: a depth
pass from the light gives each texel's first hair depth z₀ (its nearest light-space
fragment), and K layers of spacing Δ follow it, boundaries at z₀ + kΔ, k = 0 … K. On
boundary k a texel holds the alpha of its fragments with z < z₀ + kΔ (boundary 0: none),
and the texel's total beyond the last one. A point at depth z with layer coordinate
u = (z − z₀)·K/(KΔ), z₀ its own texel's, gets

    Ω = (1 − f) Ω̄_k + f Ω̄_{k+1},   k = ⌊u⌋ clamped to 0 … K − 1,  f = u − k ∈ [0, 1],

or the box-filtered total Ω̄_tot for u > K; Ω = 0 where its texel holds no hair. Ω̄ is the
3 × 3 box average of the boundary maps (`box_filter`); z₀ is not filtered. That is
`lookup = "layer"`, the paper's: every neighbour texel is read at the point's own layer.
`lookup = "depth"` reads each of the 3 × 3 texels t' at the point's depth behind that
texel's own first hair, u' = (z − z₀(t'))·K/(KΔ), k' and f' as above from u', 0 where
t' has no hair or lies outside the map, and averages the nine:

    Ω = (1/9) Σ_{t'} [(1 − f') Ω_{k'}(t') + f' Ω_{k'+1}(t')],

whose many-layer limit is `exact`'s Ω. z₀ and the layers depend on geometry alone, so
set-up (NumPy) plans the gathers and evaluation (JAX) is linear in fragment alpha, as for
opacity maps: differentiable in opacity.
"""

from __future__ import annotations

import dataclasses
import math
import numbers

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from ..._constants import SHADOW_FILTER_RADIUS
from ..._errors import SceneError
from .._projection import View
from ._base import AbstractShadowMethod, check_resolution, register_shadow_method
from ._frame import LightFrame, ShadowInputs, light_fragments
from ._opacity_maps import MAX_MAP_CELLS, accumulated_maps, opacity_maps, point_opacity

__all__ = [
    "DeepOpacityMaps",
    "DeepSetup",
    "LOOKUPS",
    "first_depths",
    "layer_coordinate",
    "deep_points",
    "filter_texels",
]

# How a point reads the 3 × 3 texels around it (docs/model.md §7): at its own layer
# (Yuksel & Keyser 2008) or at its depth behind each texel's own z₀.
LOOKUPS = ("layer", "depth")


@dataclasses.dataclass(frozen=True)
class DeepSetup:
    """What Ω needs that does not depend on opacity: light-space fragments
    `frag_strand[F]`, `frag_coverage[F]` and `frag_cell[F]` = slice · R² + texel (slice j
    holds the fragments with j ≤ u < j + 1 of their texel, slice K those with u ≥ K); per
    point the lower boundary `plane[P]` (K for points beyond the last boundary, which read
    the total), its weight `f[P]` and texel `texel[P]` (−1 outside the map or where the
    texel holds no hair); `first_depth[R²]`, each texel's z₀ (+∞ without hair). With
    `lookup = "depth"` `plane`, `f` and `texel` are `[P, 9]`, one per texel of the 3 × 3
    filter, each from that texel's z₀."""

    view: View
    frag_strand: np.ndarray
    frag_coverage: np.ndarray
    frag_cell: np.ndarray
    plane: np.ndarray
    f: np.ndarray
    texel: np.ndarray
    first_depth: np.ndarray

    @property
    def fragments(self) -> int:
        """How many light fragments it was planned from."""
        return len(self.frag_coverage)


@register_shadow_method
@dataclasses.dataclass(frozen=True)
class DeepOpacityMaps(AbstractShadowMethod):
    """`layers` (K) layers of `layer_spacing` (Δ, world units along the light) behind each
    texel's first hair, on a `resolution` × `resolution` light raster. `layer_spacing = 0`
    (the default) is the hair's light-depth extent over K, (D_N − D₀)/K: the coarsest
    spacing whose layers hold all the hair behind any texel's z₀ ≥ D₀. `lookup`: how a
    point reads its 3 × 3 texels, `"layer"` (the paper's: at its own layer coordinate in
    all nine) or `"depth"` (at its depth behind each texel's own z₀), `LOOKUPS`."""

    layers: int = 4
    resolution: int = 256
    layer_spacing: float = 0.0
    lookup: str = "depth"
    method = "deep"

    def __post_init__(self):
        k = self.layers
        if (
            isinstance(k, bool)
            or not isinstance(k, numbers.Real)
            or not math.isfinite(k)
            or int(k) != k
            or not 1 <= k <= 65536
        ):
            raise SceneError(f"shadows.layers must be an integer in [1, 65536], got {k!r}")
        spacing = self.layer_spacing
        if isinstance(spacing, bool) or not isinstance(spacing, numbers.Real) or not math.isfinite(spacing):
            raise SceneError(f"shadows.layer_spacing must be a finite number ≥ 0, got {spacing!r}")
        if spacing < 0:
            raise SceneError(
                f"shadows.layer_spacing must be ≥ 0 (0: the hair's depth extent over layers), got {spacing!r}"
            )
        if not isinstance(self.lookup, str) or self.lookup not in LOOKUPS:
            allowed = ", ".join(repr(name) for name in LOOKUPS)
            raise SceneError(f"shadows.lookup must be one of {allowed}, got {self.lookup!r}")
        object.__setattr__(self, "layers", int(k))
        object.__setattr__(self, "layer_spacing", float(spacing))
        object.__setattr__(self, "resolution", check_resolution(self.resolution))

    def planned_maps(self) -> tuple[int, str]:
        r = self.resolution  # boundaries 0 … K and the total, K + 2 maps
        return (
            self.layers + 2
        ) * r * r, f"shadows.layers = {self.layers} layers of shadows.resolution = {r}²"

    def point_lookups(self) -> int:
        side = 2 * SHADOW_FILTER_RADIUS + 1  # `filter_texels`: one entry per texel of the filter
        return side * side if self.lookup == "depth" else 1

    def depth_range(self, frame: LightFrame) -> float:
        """KΔ, the depth the K layers span behind z₀: K·`layer_spacing`, or by default the
        hair's light-depth extent D_N − D₀ (`frame.span`)."""
        return self.layers * self.layer_spacing if self.layer_spacing > 0 else frame.span

    def setup(self, inputs: ShadowInputs) -> DeepSetup:
        layers, resolution = self.layers, self.resolution
        if (layers + 2) * resolution**2 > MAX_MAP_CELLS:
            raise ValueError(
                f"{layers} layers of {resolution}² exceed {MAX_MAP_CELLS} map cells; "
                "use fewer layers or a lower resolution"
            )
        lf = light_fragments(inputs, resolution)
        depth_range = self.depth_range(lf.frame)
        pixel, depths = np.asarray(lf.frags.pixel), np.asarray(lf.frags.depths)  # planned on the host
        first = first_depths(pixel, depths, resolution)
        u = layer_coordinate(depths, first[pixel], layers, depth_range)
        # The minimum fires for fragments at or beyond the last boundary (u ≥ K): slice K,
        # counted in the texel's total only. u ≥ 0: z₀ is the texel's nearest fragment.
        j = np.minimum(np.floor(u), layers).astype(np.int64)
        if self.lookup == "depth":
            texel = filter_texels(lf.frame.xy, lf.frame.seen, resolution)
            depth = np.broadcast_to(lf.frame.depth[:, None], texel.shape)
        else:
            texel, depth = np.where(lf.inside, lf.ty * resolution + lf.tx, -1), lf.frame.depth
        plane, f, texel = deep_points(depth, texel, first, layers, depth_range)
        return DeepSetup(
            view=lf.frame.view,
            frag_strand=np.asarray(lf.frag_strand),
            frag_coverage=np.asarray(lf.frag_coverage),
            frag_cell=(j * resolution**2 + pixel).astype(np.int32),
            plane=plane.astype(np.int32),
            f=f,
            texel=texel.astype(np.int32),
            first_depth=first,
        )

    def omega(self, setup: DeepSetup, alpha):
        dtype = jnp.result_type(float)
        evaluate = _deep_depth_opacity if self.lookup == "depth" else _deep_opacity
        return evaluate(
            alpha,
            setup.frag_strand,
            jnp.asarray(setup.frag_coverage, dtype),
            setup.frag_cell,
            setup.plane,
            jnp.asarray(setup.f, dtype),
            setup.texel,
            self.layers,
            self.resolution,
        )


@eqx.filter_jit
def _deep_opacity(alpha, frag_strand, frag_coverage, frag_cell, plane, f, texel, layers, resolution):
    # Slices 0 … K accumulated behind each other: boundaries 0 … K, then the total (K + 2 maps).
    boundaries = opacity_maps(alpha[frag_strand] * frag_coverage, frag_cell, layers + 1, resolution)
    return point_opacity(boundaries, plane, f, texel)


@eqx.filter_jit
def _deep_depth_opacity(alpha, frag_strand, frag_coverage, frag_cell, plane, f, texel, layers, resolution):
    # Each texel's own boundaries (unfiltered), read at [P, 9] per-texel (k', f'), then
    # summed over the nine and divided by 9 as `exact` (its omega_exact.comp) does.
    boundaries = accumulated_maps(alpha[frag_strand] * frag_coverage, frag_cell, layers + 1, resolution)
    side = 2 * SHADOW_FILTER_RADIUS + 1
    return jnp.sum(point_opacity(boundaries, plane, f, texel), axis=-1) / (side * side)


def filter_texels(xy: np.ndarray, seen: np.ndarray, resolution: int) -> np.ndarray:
    """`[P, 9]`: the texels of each point's 3 × 3 filter (row-major, dy then dx, as the
    shaders loop), −1 outside the map or for points the light does not see."""
    r = SHADOW_FILTER_RADIUS
    # The clip keeps the cast finite (unseen points lie at ~1e300); beyond −2 or R + 1 every
    # neighbour is outside the map, as at the true texel.
    tx = np.floor(np.clip(xy[:, 0], -r - 1, resolution + r)).astype(np.int64)
    ty = np.floor(np.clip(xy[:, 1], -r - 1, resolution + r)).astype(np.int64)
    offs = np.arange(-r, r + 1)
    oy, ox = np.meshgrid(offs, offs, indexing="ij")
    nx = tx[:, None] + ox.ravel()[None, :]
    ny = ty[:, None] + oy.ravel()[None, :]
    valid = (nx >= 0) & (nx < resolution) & (ny >= 0) & (ny < resolution) & seen[:, None]
    return np.where(valid, ny * resolution + nx, -1)


def first_depths(pixel: np.ndarray, depth: np.ndarray, resolution: int) -> np.ndarray:
    """z₀ per texel (`[R²]`): the depth of its nearest light-space fragment (every
    fragment has coverage > 0), +∞ where it has none."""
    first = np.full(resolution * resolution, np.inf)
    np.minimum.at(first, pixel, depth)
    return first


def layer_coordinate(z: np.ndarray, first: np.ndarray, layers: int, depth_range: float) -> np.ndarray:
    """u = (z − z₀)·K/(KΔ): depth behind the texel's first hair in layers (as the GL
    shaders' `deep_layer_coordinate`, term by term; exactly K at z₀ + KΔ)."""
    return (z - first) * layers / depth_range


def deep_points(
    depth: np.ndarray, texel: np.ndarray, first: np.ndarray, layers: int, depth_range: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per point at light `depth` in `texel` (−1 outside the map): its lower boundary k,
    weight f and texel, the texel −1 where it holds no hair (Ω = 0 there)."""
    # Fires for points outside the map: any texel, dropped below.
    z0 = first[np.maximum(texel, 0)]
    texel = np.where((texel >= 0) & np.isfinite(z0), texel, -1)
    # Fires for the points dropped above (z₀ = ∞ there): their own depth, u = 0, any finite value.
    u = layer_coordinate(depth, np.where(texel >= 0, z0, depth), layers, depth_range)
    beyond = u > layers
    # The clips fire in front of z₀ (u < 0: boundary 0, f = 0, Ω = 0) and at z₀ + KΔ (u = K:
    # k = K − 1, f = 1); beyond it k = K and f = 1 read the texel's total.
    plane = np.where(beyond, layers, np.clip(np.floor(u), 0, layers - 1)).astype(np.int64)
    f = np.where(beyond, 1.0, np.clip(u - plane, 0.0, 1.0))
    return plane, f, texel
