"""Fragments grouped by pixel in raster order: a stable counting sort (docs/model.md §6).

Compositing reads each pixel's fragments together, front to back; the raster writes them
nearest segment first, pixels interleaved. A counting sort groups them: count the
fragments of each pixel, start each pixel's run at the sum of the counts before it, then
move every fragment, in raster order, to its pixel's next free slot. That is stable
(raster order is kept within a pixel) and O(F + H·W).

Moved straight to its pixel, each fragment is a write to one of H·W places far apart (a
million at 1024², three fields each): every write misses the caches and the address
translation buffer. So the move takes two passes, as a radix sort's digits do:

1. *bands*: every fragment goes, in raster order, to its band — a run of consecutive
   pixels holding about BAND_FRAGMENTS fragments. A few hundred bands' write positions
   stay in the caches.
2. *pixels*: each band, now contiguous and small enough for a core's caches, is grouped by
   pixel through a scratch buffer and copied back in place.

Both passes keep raster order, so the result is the one-pass counting sort's, bit for bit.
At 100k strands / 1024² (55 M fragments) this took the grouping from 1.1–1.2 s to
0.8 s (BENCHMARKS.md, "sort fragments"). NumPy has no such scatter: its stable sort of
32-bit pixel keys is two 16-bit radix passes plus a random gather per pass and per field,
4.6–8.6 s there. The loops are compiled by numba, imported on first use so that the GL
renderer and the command line's start-up do not load it.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from typing import NamedTuple, no_type_check

import numpy as np

from ._host import aligned_empty, compile_loop, host_threads, in_parallel, split_evenly

__all__ = ["Grouped", "group_by_pixel", "group_parts", "BAND_FRAGMENTS", "PARALLEL_MIN"]

# Below this many fragments one core groups them: a second thread's start-up and per-pixel
# counts cost more than they save.
PARALLEL_MIN = 1 << 20

# Fragments per band (above): a band's three fields, 1.5 MB in float32, stay in a core's
# caches while it is grouped by pixel, and 55 M fragments make 420 bands. 2^15 and 2^19
# took as long at 100k strands / 1024².
BAND_FRAGMENTS = 1 << 17


class Grouped(NamedTuple):
    """Fragments grouped by pixel: `pixel`, the pixels ascending (int32, each pixel's
    index repeated by its fragment count), and `fields` permuted alike (one array each)."""

    pixel: np.ndarray
    fields: tuple[np.ndarray, ...]


def group_by_pixel(pixel: np.ndarray, n_pixels: int, *fields: np.ndarray) -> Grouped:
    """Fragments with `pixel[F]` in [0, n_pixels), grouped by pixel in their given order.

    Returns `Grouped`: the pixels ascending (`[F]`) and each of `fields` (1-D, `[F]`, one
    to three of them) permuted alike, in arrays aligned for the CPU device (`_host`). Equals
    `field[np.argsort(pixel, kind="stable")]`. From PARALLEL_MIN fragments on, contiguous
    parts of them are scattered on every core at once (`group_parts`)."""
    if any(f.shape != pixel.shape for f in fields):
        raise ValueError(f"group_by_pixel takes one to three [F] fields, got {[f.shape for f in fields]}")
    parts = host_threads() if pixel.size >= PARALLEL_MIN else 1
    bounds = np.linspace(0, pixel.size, parts + 1).astype(np.int64)
    return group_parts(
        [(pixel[a:b], *(f[a:b] for f in fields)) for a, b in zip(bounds[:-1], bounds[1:])], n_pixels
    )


def group_parts(parts: Sequence[Sequence[np.ndarray]], n_pixels: int, capacity: int = 0) -> Grouped:
    """`group_by_pixel` of fragments given in consecutive parts, each `(pixel, *fields)`
    with one to three fields (alike in number and dtype across the parts): grouped as
    their concatenation would be, each part moved to the bands on its own thread (the
    raster's pieces, `rasterize_parts`, are read where they are); the bands are then
    grouped by pixel on every core.

    `capacity`: the outputs' length when it exceeds the fragments' F: entries F … capacity
    − 1 are padding, pixel `n_pixels` (past every pixel) and fields 0 (`fragment_bucket`)."""
    n_fields = len(parts[0]) - 1
    if not 1 <= n_fields <= 3 or any(
        len(part) != n_fields + 1 or any(f.shape != part[0].shape for f in part) for part in parts
    ):
        raise ValueError("group_by_pixel takes one to three [F] fields")
    count, to_bands, within_bands = _group_kernels()
    part_counts = [np.zeros(n_pixels, np.int64) for _ in parts]
    outside = in_parallel([functools.partial(count, part[0], c) for part, c in zip(parts, part_counts)])
    if max(outside) >= 0:  # the moves check no bounds
        bad = next(int(part[0][k]) for part, k in zip(parts, outside) if k >= 0)
        raise ValueError(f"pixel index {bad} is outside the {n_pixels} pixels [0, {n_pixels})")
    counts = np.sum(part_counts, axis=0) if len(part_counts) > 1 else part_counts[0]
    total = int(counts.sum())
    sorted_pixel = aligned_empty(max(total, capacity), np.int32)
    outs = tuple(aligned_empty(max(total, capacity), f.dtype) for f in parts[0][1:])
    sorted_pixel[total:] = n_pixels
    for out in outs:
        out[total:] = 0
    if not total:  # no fragments (or no pixels): nothing to move
        return Grouped(sorted_pixel, outs)
    band_pixel = _bands(counts)  # each band's first pixel, and n_pixels
    # Each part's and all parts' fragments per band.
    part_bands = [np.add.reduceat(c, band_pixel[:-1]) for c in part_counts]
    band_sizes = np.sum(part_bands, axis=0) if len(part_bands) > 1 else part_bands[0]
    band_start = np.zeros(band_sizes.size + 1, np.int64)
    np.cumsum(band_sizes, out=band_start[1:])
    # The loops take three fields; a missing one repeats the last (written twice, alike).
    outs3 = (outs + (outs[-1],) * 2)[:3]

    # Pass 1: each part's fragments to their bands, after the parts before it (its own
    # slots in every band: no lock is needed). The pixels ride along for pass 2.
    band_of = np.repeat(np.arange(band_sizes.size, dtype=np.int32), np.diff(band_pixel))
    tasks = []
    slot = band_start[:-1].copy()
    for part, own in zip(parts, part_bands):
        fields = tuple(part[1:])
        ins3 = (fields + (fields[-1],) * 2)[:3]
        tasks.append(functools.partial(to_bands, part[0], band_of, slot.copy(), *ins3, sorted_pixel, *outs3))
        slot += own
    in_parallel(tasks)

    # Pass 2: the bands by pixel, runs of bands about equal in fragments on each core.
    runs = split_evenly(band_sizes, host_threads() if total >= PARALLEL_MIN else 1)
    tasks = []
    for lo, hi in zip(runs[:-1], runs[1:]):
        if hi == lo:
            continue
        largest = int(band_sizes[lo:hi].max())
        scratch = tuple(np.empty(largest, o.dtype) for o in outs3)
        widest = int(np.diff(band_pixel[lo : hi + 1]).max())
        tasks.append(
            functools.partial(
                within_bands,
                lo,
                hi,
                band_pixel,
                band_start,
                counts,
                sorted_pixel,
                *outs3,
                *scratch,
                np.empty(widest, np.int64),
            )
        )
    in_parallel(tasks)
    return Grouped(sorted_pixel, outs)


def _bands(counts: np.ndarray) -> np.ndarray:
    """Bounds `[0, …, n_pixels]` of runs of consecutive pixels holding about
    BAND_FRAGMENTS fragments each (a pixel with more is a band of its own)."""
    cum = np.cumsum(counts)
    inner = np.searchsorted(cum, np.arange(BAND_FRAGMENTS, cum[-1], BAND_FRAGMENTS), side="right")
    return np.unique(np.concatenate([[0], inner, [counts.size]]))


@functools.cache
def _group_kernels():
    """The loops, compiled on first use (cached on disk, `compile_loop`): `count` adds
    each fragment to its pixel's count and returns the position of the first pixel index
    outside the counts (−1 when none is); `to_bands` moves every fragment of a part, in
    order, to its band's next free slot (`slot`, advanced); `within_bands` groups bands
    [lo, hi) by pixel in place, through scratch arrays as long as the largest of them, and
    writes each pixel's index repeated by its count."""

    # no_type_check: the tests' jaxtyping hook would otherwise wrap the loops before numba
    # compiles them.
    @compile_loop()
    @no_type_check
    def count(pixel, counts):
        for f in range(pixel.size):
            p = pixel[f]
            if p < 0 or p >= counts.size:
                return f
            counts[p] += 1
        return -1

    @compile_loop()
    @no_type_check
    def to_bands(pixel, band_of, slot, a, b, c, out_pixel, out_a, out_b, out_c):
        for f in range(pixel.size):
            p = pixel[f]
            k = band_of[p]
            s = slot[k]
            slot[k] = s + 1
            out_pixel[s] = p
            out_a[s] = a[f]
            out_b[s] = b[f]
            out_c[s] = c[f]

    @compile_loop()
    @no_type_check
    def within_bands(lo, hi, band_pixel, band_start, counts, pixel, a, b, c, sa, sb, sc, slot):
        for k in range(lo, hi):
            first, end = band_start[k], band_start[k + 1]
            p0, p1 = band_pixel[k], band_pixel[k + 1]
            s = 0
            for p in range(p0, p1):
                slot[p - p0] = s
                s += counts[p]
            for f in range(first, end):
                q = pixel[f] - p0
                s = slot[q]
                slot[q] = s + 1
                sa[s] = a[f]
                sb[s] = b[f]
                sc[s] = c[f]
            for j in range(end - first):
                a[first + j] = sa[j]
                b[first + j] = sb[j]
                c[first + j] = sc[j]
            f = first
            for p in range(p0, p1):
                for _ in range(counts[p]):
                    pixel[f] = p
                    f += 1

    return count, to_bands, within_bands
