"""The compositing weights at concrete opacities, on the host (docs/model.md §6).

A render composites at the scene's own strand opacities, which nothing differentiates: its
weights w_k = α_k T_k and each pixel's T are computed here by one compiled loop over the
fragments (grouped by pixel, front to back within a pixel), in the working precision, T
multiplied fragment after fragment. The loop also leaves out, as it goes, the fragments
seen through less than the cutoff (`_hidden`), writing the others to aligned buffers the
geometry stage shares with JAX (`_host`).

Multiplied in order, a pixel's T rounds the same wherever its run lies in the array: the
fragments the set-up left out before grouping (`_seen`) move no weight and no pixel. JAX's
product scan (`pixel_weights`), which a traced α needs, forms the same products by a tree
laid over array positions; the two agree within the rounding of a product
(tests/geometry/test_weights.py).
"""

from __future__ import annotations

import functools
from typing import NamedTuple, no_type_check

import numpy as np

from ._capacity import fragment_bucket
from ._host import aligned_empty, compile_loop

__all__ = ["HostWeights", "host_weights"]


class HostWeights(NamedTuple):
    """`host_weights`' result: the fragments seen (`pixel`, `i0`, `t` and their `weight`,
    padded to their `fragment_bucket` with pixel H·W and zeros), each pixel's
    `transmittance` and `alpha_channel` (`[H·W]`), in the working precision."""

    pixel: np.ndarray
    i0: np.ndarray
    t: np.ndarray
    weight: np.ndarray
    transmittance: np.ndarray
    alpha_channel: np.ndarray


def host_weights(alpha, strand_of_point, padded, opaque, hidden, cutoff: float, dtype) -> HostWeights:
    """The weights of the set-up's `padded` fragments (`PaddedFragments`: pixel, i0,
    coverage, t) at the per-strand opacities `alpha`, without those seen through less
    than `cutoff` (`[S]`; `strand_of_point` `[P]`); `opaque` (`[H·W]` bool) the
    occluder's pixels, `hidden` (`[H·W]` or None) the transmittance of the fragments the
    set-up left out (`GeometrySetup.hidden`), multiplied into each pixel's."""
    dtype = np.dtype(dtype)
    pixel, i0, coverage, t = (np.asarray(x) for x in padded)
    hw = opaque.shape[0]
    alpha, strand_of_point = np.asarray(alpha, dtype), np.asarray(strand_of_point, np.int32)
    coverage, t = np.asarray(coverage, dtype), np.asarray(t, dtype)
    weigh, weigh_seen = _loops(dtype.name)
    transmittance = np.ones(hw, dtype)
    n = pixel.shape[0]
    if cutoff > 0:  # the seen ones into new buffers, in one pass: the set-up's stay whole
        fields: tuple[np.ndarray, ...] = tuple(
            aligned_empty(n, d) for d in (np.int32, np.int32, dtype, dtype)
        )
        args = (alpha, strand_of_point, pixel, i0, coverage, t, hw, dtype.type(cutoff), transmittance)
        kept = weigh_seen(*args, *fields)
        size = fragment_bucket(kept)
        for field, fill in zip(fields, (hw, 0, 0, 0)):
            field[kept:size] = fill  # the bucket's padding
        fields = tuple(field[:size] for field in fields)
    else:  # every fragment kept: the set-up's own buffers, and the weights
        weight = aligned_empty(n, dtype)
        count = weigh(alpha, strand_of_point, pixel, i0, coverage, hw, transmittance, weight)
        weight[count:] = 0  # the bucket's padding
        fields = (pixel, i0, t, weight)
    if hidden is not None:
        transmittance *= np.asarray(hidden).astype(dtype)
    one = dtype.type(1)
    alpha_channel = one - transmittance * (one - opaque.astype(dtype))
    p, i, tt, w = fields
    return HostWeights(p, i, tt, w, transmittance, alpha_channel)


@functools.cache
def _loops(dtype_name: str):
    """The weights' loops compiled by numba for floats of `dtype_name` (on first use;
    cached on disk, `compile_loop`); every constant has that type, so no product widens:
    `weigh` writes every fragment's weight, `weigh_seen` the fragments seen through at
    least the cutoff with their weights; both each pixel's T."""
    F = np.float32 if dtype_name == "float32" else np.float64
    one = F(1.0)

    @compile_loop(error_model="numpy", inline="always")
    @no_type_check
    def over(alpha, strand_of_point, i0, coverage, p, k, transmittance):
        """(α, w = α·T) of fragment k at pixel p, whose (1 − α) then dims T."""
        a = alpha[strand_of_point[i0[k]]] * coverage[k]
        seen_through = transmittance[p]
        transmittance[p] = seen_through * (one - a)
        return a, a * seen_through

    @compile_loop(error_model="numpy")
    @no_type_check
    def weigh(alpha, strand_of_point, pixel, i0, coverage, hw, transmittance, weight):
        """The number of fragments (before the bucket's padding)."""
        for k in range(pixel.size):
            if pixel[k] >= hw:
                return k  # the bucket's padding, after every fragment
            weight[k] = over(alpha, strand_of_point, i0, coverage, pixel[k], k, transmittance)[1]
        return pixel.size

    @compile_loop(error_model="numpy")
    @no_type_check
    def weigh_seen(alpha, strand_of_point, pixel, i0, coverage, t, hw, cutoff, transmittance, *out):
        """The number of fragments seen, written to `out` (pixel, i0, t, weight)."""
        out_pixel, out_i0, out_t, out_weight = out
        kept = 0
        for k in range(pixel.size):
            p = pixel[k]
            if p >= hw:
                break  # the bucket's padding, after every fragment
            a, weight = over(alpha, strand_of_point, i0, coverage, p, k, transmittance)
            # T ≥ c as w ≥ c·α, the JAX path's test: α = 0 counts as seen (it adds 0).
            if weight >= cutoff * a:
                out_pixel[kept], out_i0[kept], out_t[kept], out_weight[kept] = p, i0[k], t[k], weight
                kept += 1
        return kept

    return weigh, weigh_seen
