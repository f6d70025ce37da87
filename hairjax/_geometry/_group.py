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
from collections.abc import Sequence
from typing import no_type_check

import numpy as np

from ._host import aligned_empty, compile_loop, host_threads, in_parallel

__all__ = ["group_by_pixel", "group_parts", "PARALLEL_MIN"]

# Below this many fragments one core groups them: a second thread's start-up and per-pixel
# counts cost more than they save.
PARALLEL_MIN = 1 << 20


def group_by_pixel(
    pixel: np.ndarray, n_pixels: int, *fields: np.ndarray
) -> tuple[np.ndarray, tuple[np.ndarray, ...]]:
    """Fragments with `pixel[F]` in [0, n_pixels), grouped by pixel in their given order.

    Returns `(sorted_pixel, grouped)`: the pixels ascending (`[F]` int32, each pixel's
    index repeated by its fragment count) and each of `fields` (1-D, `[F]`, one to three
    of them) permuted alike, in arrays aligned for the CPU device (`_host`). Equals
    `field[np.argsort(pixel, kind="stable")]`. From PARALLEL_MIN fragments on, contiguous
    parts of them are scattered on every core at once (`group_parts`)."""
    if any(f.shape != pixel.shape for f in fields):
        raise ValueError(f"group_by_pixel takes one to three [F] fields, got {[f.shape for f in fields]}")
    parts = host_threads() if pixel.size >= PARALLEL_MIN else 1
    bounds = np.linspace(0, pixel.size, parts + 1).astype(np.int64)
    return group_parts(
        [(pixel[a:b], *(f[a:b] for f in fields)) for a, b in zip(bounds[:-1], bounds[1:])], n_pixels
    )


def group_parts(
    parts: Sequence[Sequence[np.ndarray]], n_pixels: int
) -> tuple[np.ndarray, tuple[np.ndarray, ...]]:
    """`group_by_pixel` of fragments given in consecutive parts, each `(pixel, *fields)`
    with one to three fields (alike in number and dtype across the parts): grouped as
    their concatenation would be, each part scattered on its own thread. Each part counts
    its fragments per pixel, so it owns its own slots in every pixel's run and no lock is
    needed (the raster's pieces, `rasterize_parts`, are read where they are)."""
    n_fields = len(parts[0]) - 1
    if not 1 <= n_fields <= 3 or any(
        len(part) != n_fields + 1 or any(f.shape != part[0].shape for f in part) for part in parts
    ):
        raise ValueError("group_by_pixel takes one to three [F] fields")
    part_counts = [np.bincount(part[0], minlength=n_pixels) for part in parts]
    if any(c.size != n_pixels for c in part_counts):  # a pixel ≥ n_pixels: the loop checks no bounds
        beyond = max(int(part[0].max()) for part in parts if part[0].size)
        raise ValueError(f"pixel indices reach {beyond}, beyond the {n_pixels} pixels")
    counts = np.sum(part_counts, axis=0) if len(part_counts) > 1 else part_counts[0]
    # Where each part's first fragment of each pixel goes: after the pixels before it and
    # after the parts before it.
    start = np.zeros(n_pixels, np.int64)
    np.cumsum(counts[:-1], out=start[1:])
    total = sum(part[0].size for part in parts)
    sorted_pixel = aligned_empty(total, np.int32)
    outs = tuple(aligned_empty(total, f.dtype) for f in parts[0][1:])
    # The loop takes three fields; a missing one repeats the last (written twice, alike).
    outs3 = (outs + (outs[-1],) * 2)[:3]
    fill_runs, scatter = _group_kernels()
    tasks = []
    for part, own in zip(parts, part_counts):
        fields = tuple(part[1:])
        ins3 = (fields + (fields[-1],) * 2)[:3]
        tasks.append(functools.partial(scatter, part[0], start.copy(), *ins3, *outs3))
        start += own
    in_parallel([*tasks, functools.partial(fill_runs, counts, sorted_pixel)])
    return sorted_pixel, outs


@functools.cache
def _group_kernels():
    """The counting sort's loops, compiled on first use (cached on disk, `compile_loop`):
    `fill_runs` writes each pixel's index repeated by its count, `scatter` moves every
    fragment of a part, in order, to its pixel's next free slot (`start`, advanced)."""

    # no_type_check: the tests' jaxtyping hook would otherwise wrap the loops before numba
    # compiles them.
    @compile_loop()
    @no_type_check
    def fill_runs(counts, sorted_pixel):
        slot = 0
        for p in range(counts.size):
            for _ in range(counts[p]):
                sorted_pixel[slot] = p
                slot += 1

    @compile_loop()
    @no_type_check
    def scatter(pixel, start, a, b, c, out_a, out_b, out_c):
        for f in range(pixel.size):
            p = pixel[f]
            slot = start[p]
            start[p] = slot + 1
            out_a[slot] = a[f]
            out_b[slot] = b[f]
            out_c[slot] = c[f]

    return fill_runs, scatter
