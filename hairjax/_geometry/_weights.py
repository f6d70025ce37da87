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
    weigh, compact = _loops(dtype.name)
    weight = aligned_empty(pixel.shape[0], dtype)
    transmittance = np.ones(hw, dtype)
    cutoff = dtype.type(cutoff)
    count, kept = weigh(alpha, strand_of_point, pixel, i0, coverage, hw, cutoff, transmittance, weight)
    weight[count:] = 0  # the bucket's padding
    fields: tuple[np.ndarray, ...] = (pixel, i0, t, weight)
    if kept < count:  # into new buffers: the set-up's own stay whole
        fields = tuple(aligned_empty(fragment_bucket(kept), f.dtype) for f in fields)
        compact(alpha, strand_of_point, pixel, i0, coverage, t, weight, count, cutoff, *fields)
        for field, fill in zip(fields, (hw, 0, 0, 0)):
            field[kept:] = fill
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
    `weigh`, each fragment's weight and each pixel's T; `compact`, the seen fragments
    moved to new buffers."""
    F = np.float32 if dtype_name == "float32" else np.float64
    one = F(1.0)

    @compile_loop(error_model="numpy")
    @no_type_check
    def weigh(alpha, strand_of_point, pixel, i0, coverage, hw, cutoff, transmittance, weight):
        """(fragments before the padding, those seen through at least `cutoff`)."""
        kept = 0
        count = 0
        for k in range(pixel.size):
            p = pixel[k]
            if p >= hw:
                break  # the bucket's padding, after every fragment
            a = alpha[strand_of_point[i0[k]]] * coverage[k]
            seen_through = transmittance[p]
            weight[k] = a * seen_through
            transmittance[p] = seen_through * (one - a)
            # T ≥ c as w ≥ c·α, the JAX path's test: α = 0 counts as seen (it adds 0).
            if weight[k] >= cutoff * a:
                kept += 1
            count += 1
        return count, kept

    @compile_loop(error_model="numpy")
    @no_type_check
    def compact(alpha, strand_of_point, pixel, i0, coverage, t, weight, count, cutoff, *out):
        out_pixel, out_i0, out_t, out_weight = out
        kept = 0
        for k in range(count):
            a = alpha[strand_of_point[i0[k]]] * coverage[k]
            if weight[k] >= cutoff * a:
                out_pixel[kept], out_i0[kept], out_t[kept], out_weight[kept] = (
                    pixel[k],
                    i0[k],
                    t[k],
                    weight[k],
                )
                kept += 1

    return weigh, compact
