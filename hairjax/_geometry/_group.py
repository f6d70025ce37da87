"""Fragments grouped by pixel in raster order: a stable counting sort (docs/model.md §6).

Compositing reads each pixel's fragments together, front to back; the raster writes them
nearest segment first, pixels interleaved. A counting sort groups them in one pass: count
the fragments of each pixel, start each pixel's run at the sum of the counts before it,
then move every fragment, in raster order, to its pixel's next free slot. That is stable
(raster order is kept within a pixel) and O(F + H·W), one sequential read and one write
per field and fragment.

NumPy has no such scatter. Its stable sort of 32-bit pixel keys is two 16-bit radix passes
plus a random gather per pass and per field: 4.6–8.6 s for the 55 M fragments of 100k
strands at 1024², against 1.1 s for this loop (BENCHMARKS.md, "sort fragments"). The loop
is compiled by numba, imported on first use so that the GL renderer and the command
line's start-up do not load it.
"""

from __future__ import annotations

import functools
from typing import no_type_check

import numpy as np

from ._host import aligned_empty

__all__ = ["group_by_pixel"]


def group_by_pixel(
    pixel: np.ndarray, n_pixels: int, *fields: np.ndarray
) -> tuple[np.ndarray, tuple[np.ndarray, ...]]:
    """Fragments with `pixel[F]` in [0, n_pixels), grouped by pixel in their given order.

    Returns `(sorted_pixel, grouped)`: the pixels ascending (`[F]` int32, each pixel's
    index repeated by its fragment count) and each of `fields` (1-D, `[F]`, one to three
    of them) permuted alike, in arrays aligned for the CPU device (`_host`). Equals
    `field[np.argsort(pixel, kind="stable")]`."""
    if not 1 <= len(fields) <= 3 or any(f.shape != pixel.shape for f in fields):
        raise ValueError(f"group_by_pixel takes one to three [F] fields, got {[f.shape for f in fields]}")
    counts = np.bincount(pixel, minlength=n_pixels)  # raises for a negative pixel
    if counts.size != n_pixels:  # a pixel ≥ n_pixels: the kernel checks no bounds
        raise ValueError(f"pixel indices reach {counts.size - 1}, beyond the {n_pixels} pixels")
    sorted_pixel = aligned_empty(pixel.size, np.int32)
    outs = tuple(aligned_empty(pixel.size, f.dtype) for f in fields)
    # The kernel takes three fields; a missing one repeats the last (written twice, alike).
    ins3 = (fields + (fields[-1],) * 2)[:3]
    outs3 = (outs + (outs[-1],) * 2)[:3]
    _group_kernel()(pixel, counts, sorted_pixel, *ins3, *outs3)
    return sorted_pixel, outs


@functools.cache
def _group_kernel():
    """The counting sort's two passes, compiled on first use (cached on disk by numba)."""
    import numba

    # no_type_check: the tests' jaxtyping hook would otherwise wrap the loop before numba
    # compiles it.
    @numba.njit(cache=True, nogil=True)
    @no_type_check
    def group(pixel, counts, sorted_pixel, a, b, c, out_a, out_b, out_c):
        # Each pixel's run: its index repeated by its count, and where its run starts.
        start = np.empty(counts.size, np.int64)
        slot = 0
        for p in range(counts.size):
            start[p] = slot
            for _ in range(counts[p]):
                sorted_pixel[slot] = p
                slot += 1
        # Every fragment, in the given order, to its pixel's next free slot.
        for f in range(pixel.size):
            p = pixel[f]
            slot = start[p]
            start[p] = slot + 1
            out_a[slot] = a[f]
            out_b[slot] = b[f]
            out_c[slot] = c[f]

    return group
