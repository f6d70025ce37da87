"""`method = "opacity-maps"`: kim-2003 §4's opacity shadow maps, Routine 2 (docs/model.md §7).

Ω(D, texel) is the summed fragment alpha, in the light's raster, of everything nearer the
light than depth D. Maps sit on the planes D_i = D_0 + iΔ, i = 0..N, Δ = (D_N − D_0)/N,
between the nearest (D_0) and farthest (D_N) strand point; a point at depth z with
D_i ≤ z ≤ D_{i+1} gets

    Ω = (1 − f) Ω̄(D_i) + f Ω̄(D_{i+1}),   f = (z − D_i)/Δ,

with Ω̄ the 3 × 3 box average around the point's texel (texels outside the map count 0).
Set-up (NumPy, geometry only) plans the gathers; evaluation (JAX) is linear in fragment
alpha, so Ω is differentiable in opacity. A render's set-up, planned for the scene's own
opacities (`ShadowInputs.opacity`), sums each slice's fragment alpha on the host instead,
in fragment order as JAX's segment sum does, bit for bit, and keeps no fragments.
"""

from __future__ import annotations

import dataclasses
import functools
from typing import no_type_check

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, Int

from ..._constants import SHADOW_FILTER_RADIUS
from .._host import compile_loop
from .._projection import View
from .._raster import Arrays
from ._base import AbstractShadowMethod, check_resolution, register_shadow_method
from ._frame import LightFragments, LightFrame, ShadowInputs, light_fragments

__all__ = [
    "OpacityMaps",
    "OpacityMapSetup",
    "point_planes",
    "box_filter",
    "opacity_maps",
    "accumulated_maps",
    "stacked_maps",
    "point_opacity",
    "MAX_MAP_CELLS",
]

# (N + 1) · R² map cells at most: 1 GiB in float32.
MAX_MAP_CELLS = 1 << 28


@dataclasses.dataclass(frozen=True)
class OpacityMapSetup:
    """What Ω needs: per point the plane index `plane[P]`, its weight `f[P]` and texel
    `texel[P]` (−1 outside); and either the light-space fragments `frag_strand[F]`,
    `frag_coverage[F]` and `frag_cell[F]` = slice · R² + texel (slice N: beyond the last
    plane, dropped), for any opacity, or, planned for given opacities (a render's), their
    fragment alpha summed per cell, `slices[(N + 1) · R²]` in JAX's float precision.
    `fragments`: how many light fragments it was planned from."""

    view: View
    plane: np.ndarray
    f: np.ndarray
    texel: np.ndarray
    fragments: int
    frag_strand: Arrays | None = None
    frag_coverage: Arrays | None = None
    frag_cell: Arrays | None = None
    slices: np.ndarray | None = None


@register_shadow_method
@dataclasses.dataclass(frozen=True)
class OpacityMaps(AbstractShadowMethod):
    """`maps` (N) opacity maps of `resolution` × `resolution` texels."""

    maps: int = 64
    resolution: int = 256
    method = "opacity-maps"
    rasterizes_on_device = True

    def __post_init__(self):
        n = self.maps
        if isinstance(n, bool) or int(n) != n or not 1 <= n <= 65536:
            from ..._errors import SceneError

            raise SceneError(f"shadows.maps must be an integer in [1, 65536], got {n!r}")
        object.__setattr__(self, "maps", int(n))
        object.__setattr__(self, "resolution", check_resolution(self.resolution))

    def planned_maps(self) -> tuple[int, str]:
        r = self.resolution
        return (self.maps + 1) * r * r, f"shadows.maps = {self.maps} maps of shadows.resolution = {r}²"

    def setup(self, inputs: ShadowInputs) -> OpacityMapSetup:
        maps, resolution = self.maps, self.resolution
        if (maps + 1) * resolution**2 > MAX_MAP_CELLS:
            raise ValueError(
                f"{maps} maps of {resolution}² exceed {MAX_MAP_CELLS} cells; "
                "use fewer maps or a lower resolution"
            )
        on_device = self.rasterizes_on_device and inputs.placement == "device"
        lf = light_fragments(inputs, resolution, on_device=on_device)
        plane, f = point_planes(lf.frame, maps)
        # Planned for the scene's opacities (a render's), the fragments are summed here.
        opacity = None if on_device else inputs.opacity
        slices = None if opacity is None else _summed_slices(lf, opacity, maps, resolution)
        summed = slices is not None
        return OpacityMapSetup(
            view=lf.frame.view,
            plane=plane.astype(np.int32),
            f=f,
            texel=np.where(lf.inside, lf.ty * resolution + lf.tx, -1).astype(np.int32),
            fragments=lf.count,
            frag_strand=None if summed else lf.frag_strand,
            frag_coverage=None if summed else lf.frag_coverage,
            frag_cell=None if summed else _frag_cells(lf, maps, resolution),
            slices=slices,
        )

    def omega(self, setup: OpacityMapSetup, alpha):
        dtype = jnp.result_type(float)
        if setup.slices is not None:  # planned for the scene's opacities: summed already
            return _summed_opacity(
                jnp.asarray(setup.slices, dtype),
                setup.plane,
                jnp.asarray(setup.f, dtype),
                setup.texel,
                self.maps,
                self.resolution,
            )
        return _map_opacity(
            alpha,
            setup.frag_strand,
            jnp.asarray(setup.frag_coverage, dtype),
            setup.frag_cell,
            setup.plane,
            jnp.asarray(setup.f, dtype),
            setup.texel,
            self.maps,
            self.resolution,
        )


@eqx.filter_jit
def _map_opacity(alpha, frag_strand, frag_coverage, frag_cell, plane, f, texel, maps, resolution):
    omega = opacity_maps(alpha[frag_strand] * frag_coverage, frag_cell, maps, resolution)
    return point_opacity(omega, plane, f, texel)


@eqx.filter_jit
def _summed_opacity(slices, plane, f, texel, maps, resolution):
    return point_opacity(box_filter(stacked_maps(slices, maps, resolution)), plane, f, texel)


def _summed_slices(lf: LightFragments, opacity: np.ndarray, maps: int, resolution: int) -> np.ndarray:
    """`accumulated_maps`' per-cell sums at the strand `opacity`, on the host: one
    compiled pass over the light fragments (`_sums_loop`), piece after piece as the raster
    wrote them (not joined), in their order, with JAX's
    float precision and its roundings (the factor's product in float64, as NumPy
    promotes it, rounded once; α times it rounded; then added), so the sums equal JAX's
    segment sum bit for bit, without the per-fragment gathers and cells."""
    dtype = np.dtype(jnp.result_type(float))
    seg_alpha = np.asarray(opacity).astype(dtype)[lf.segment_strand]
    factor = np.empty(0) if lf.segment_factor is None else np.asarray(lf.segment_factor, np.float64)
    slices = np.zeros((maps + 1) * resolution * resolution, dtype)
    sums = _sums_loop(dtype.name)
    for piece in lf.pieces:
        depth = piece.depths
        cells = _cell_params(lf.frame, depth.dtype, maps, resolution)
        sums(
            depth,
            piece.pixel,
            piece.coverage.astype(dtype, copy=False),
            piece.segment,
            seg_alpha,
            factor,
            cells,
            slices,
        )
    return slices


def _cell_params(frame: LightFrame, depth_dtype, maps: int, resolution: int) -> tuple:
    """`cell_of`'s (zmin, maps, span, texels), the first three in the depths' precision:
    slice_coordinate's arithmetic, as the JAX path's."""
    f = np.dtype(depth_dtype).type
    return f(frame.zmin), f(maps), f(frame.span), np.int32(resolution**2)


def _frag_cells(lf: LightFragments, maps: int, resolution: int):
    """Each light fragment's map cell j·R² + pixel (int32: (N + 1)·R² ≤ MAX_MAP_CELLS <
    2³¹), j its slice, `floor(slice_coordinate)` clipped to 0 … N: a fragment in
    [D_j, D_{j+1}) counts towards planes j + 1 … N (strictly nearer). The clip fires only
    through rounding (a depth ulps below D₀ → slice 0); D_N gives N. On the host one
    compiled pass (`_cells_loop`) writes them: NumPy's six passes, each into fresh pages,
    took 0.2–0.4 s for the 16.6 M fragments of 100k strands."""
    frame, depth, pixel = lf.frame, lf.frags.depths, lf.frags.pixel
    if isinstance(depth, jax.Array):
        j = jnp.clip(jnp.floor(frame.slice_coordinate(depth, maps)), 0, maps).astype(np.int32)
        return j * np.int32(resolution**2) + pixel
    cell = np.empty(depth.shape, np.int32)
    _cells_loop()(depth, pixel, _cell_params(frame, depth.dtype, maps, resolution), cell)
    return cell


@functools.cache
def _cell_of():
    """`cell_of(depth, pixel, zmin, maps, span, texels)`: a fragment's map cell
    (`_frag_cells`), compiled by numba to be inlined in the host passes."""

    @compile_loop(error_model="numpy", inline="always")
    @no_type_check
    def cell_of(depth, pixel, zmin, maps, span, texels):
        u = np.floor((depth - zmin) * maps / span)  # slice_coordinate, in its precision
        return np.int32(min(max(u, 0), maps)) * texels + pixel

    return cell_of


@functools.cache
def _cells_loop():
    """`_frag_cells`' host pass compiled by numba (on first use; cached on disk)."""
    cell_of = _cell_of()

    @compile_loop(error_model="numpy")
    @no_type_check
    def cells(depth, pixel, frame, out):
        zmin, maps, span, texels = frame
        for k in range(depth.size):
            out[k] = cell_of(depth[k], pixel[k], zmin, maps, span, texels)

    return cells


@functools.cache
def _sums_loop(dtype_name: str):
    """`_summed_slices`' host pass compiled by numba for sums in `dtype_name`. Compiled
    without contraction: a fused multiply-add would round α·c and the sum once, where
    JAX's product and scatter-add round each."""
    F = np.float32 if dtype_name == "float32" else np.float64
    cell_of = _cell_of()

    @compile_loop(error_model="numpy")
    @no_type_check
    def sums(depth, pixel, coverage, segment, seg_alpha, factor, frame, out):
        zmin, maps, span, texels = frame
        with_factor = factor.size > 0
        for k in range(depth.size):
            seg = segment[k]
            c = F(coverage[k] * factor[seg]) if with_factor else coverage[k]
            out[cell_of(depth[k], pixel[k], zmin, maps, span, texels)] += seg_alpha[seg] * c

    return sums


def point_planes(frame: LightFrame, maps: int) -> tuple[np.ndarray, np.ndarray]:
    """Each point's plane i (its slice, clamped to 0 … N − 1) and weight f ∈ [0, 1]."""
    u = frame.slice_coordinate(frame.depth, maps)
    # The clips fire at D_N (u = N: plane N − 1, f = 1) and for unseen points (u < 0: 0, 0).
    plane = np.clip(np.floor(u), 0, maps - 1).astype(np.int64)
    return plane, np.clip(u - plane, 0.0, 1.0)


def box_filter(maps: Float[Array, "n r r"]) -> Float[Array, "n r r"]:
    """(2r + 1)² box average over texels, zero outside the map."""
    r = SHADOW_FILTER_RADIUS
    k = 2 * r + 1
    padded = jnp.pad(maps, ((0, 0), (r, r), (r, r)))
    # Each sum starts from its first term (not 0): an Array throughout, the same values.
    h, w = maps.shape[1], maps.shape[2]
    rows = sum((padded[:, i : i + h, :] for i in range(1, k)), start=padded[:, :h, :])
    return sum((rows[:, :, i : i + w] for i in range(1, k)), start=rows[:, :, :w]) / (k * k)


def opacity_maps(
    frag_alpha: Float[Array, " f"], frag_cell: Int[Array, " f"], maps: int, resolution: int
) -> Float[Array, "n1 r r"]:
    """Box-filtered Ω̄ on the N + 1 planes (plane 0 is empty): kim-2003 Routine 2's
    accumulation, with each slice added to the ones behind it (GL_ONE, GL_ONE)."""
    return box_filter(accumulated_maps(frag_alpha, frag_cell, maps, resolution))


def accumulated_maps(
    frag_alpha: Float[Array, " f"], frag_cell: Int[Array, " f"], maps: int, resolution: int
) -> Float[Array, "n1 r r"]:
    """`opacity_maps` per texel, before the box filter: plane i holds the texel's alpha
    in slices 0 … i − 1."""
    cells = resolution * resolution
    slices = jax.ops.segment_sum(frag_alpha, frag_cell, num_segments=(maps + 1) * cells)
    return stacked_maps(slices, maps, resolution)


def stacked_maps(slices: Float[Array, " c"], maps: int, resolution: int) -> Float[Array, "n1 r r"]:
    """`accumulated_maps` from each cell's summed fragment alpha (`[(N + 1) · R²]`, slice
    N dropped): plane i holds slices 0 … i − 1."""
    slices = slices.reshape(maps + 1, resolution, resolution)[:maps]
    return jnp.concatenate([jnp.zeros_like(slices[:1]), jnp.cumsum(slices, axis=0)])


def point_opacity(
    maps: Float[Array, "n1 r r"], plane: Int[Array, "*p"], f: Float[Array, "*p"], texel: Int[Array, "*p"]
) -> Float[Array, "*p"]:
    """Ω at points: linear interpolation between the two planes around each point (any
    shape of `plane`, `f`, `texel`: elementwise)."""
    flat = maps.reshape(maps.shape[0], -1)
    safe = jnp.maximum(texel, 0)  # fires for texel −1 (outside): any valid index, dropped below
    omega = (1 - f) * flat[plane, safe] + f * flat[plane + 1, safe]
    # Fires for points outside the light's map (behind a point light): no shadow.
    return jnp.where(texel >= 0, omega, 0.0)
