"""Ribbon rasterisation with analytic coverage (kim-2003 §2; docs/model.md §5).

A segment (x0, y0) → (x1, y1) in pixel coordinates is a screen-aligned ribbon of width w.
A pixel centre c, at signed position s = (c − p0)·u along the segment and distance
d = |(c − p0) × u| from its line, is covered by

    coverage = clamp(min(d + ½, w/2) − max(d − ½, −w/2), 0, 1)   if 0 ≤ s < L, else 0,

the overlap of a unit pixel box aligned with the ribbon and the ribbon's cross-section.
The width may differ at the two ends (ribbons of world-space width, `ribbon_widths`): then
w = (1 − t)·w₀ + t·w₁ at the pixel centre's t = s/L.
Along the segment, the half-open interval [0, L) gives every pixel to exactly one of two
collinear neighbours: a straight strand drawn as 1 or 8 segments covers the same pixels
with the same coverage (no double-covered joints, no gaps).

Geometry only, no gradients flow through here: the segments' columns are counted in NumPy
float64; the per-pixel maths runs in JAX's default float precision (float32, or float64
with x64 on) in one loop over the segments' columns and the candidate rows around the
line in each, compiled by numba (`_raster_loop`), which writes only the covered
candidates. (An XLA kernel over every candidate followed by NumPy's compaction did the
same work before, 2.5–4× slower: BENCHMARKS.md, "rasterize".) The coverage is one formula
for that loop and the device's XLA program (`_coverage`).
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable
from typing import no_type_check

import jax
import jax.numpy as jnp
import numpy as np

from ._capacity import check_memory
from ._host import compile_loop, host_threads, in_parallel, split_evenly
from ._raster_loop import coverage_loop, raster_loop
from ._raster_plan import raster_plan, ribbon_widths

__all__ = [
    "Arrays",
    "Fragments",
    "rasterize",
    "joined",
    "rasterize_parts",
    "count_fragments",
    "ribbon_coverage",
    "ribbon_widths",
    "PARALLEL_MIN",
    "EVERY_COVERED",
]

# NumPy on the host (the compiled loops'), JAX arrays on a device (`_device_raster`).
Arrays = np.ndarray | jax.Array

# Below this many candidates one thread rasterises: more cost more than they save.
PARALLEL_MIN = 1 << 20

# `raster_loop`'s `seen` that writes every covered candidate: no occluder, no cut.
EVERY_COVERED = (np.empty(0), np.empty(0), np.empty(0), np.empty(0), 0.0)


def ribbon_coverage(d, width) -> np.ndarray:
    """Coverage of a unit box at distance `d` from the ribbon axis by a ribbon of `width`
    (docs/model.md §5), elementwise, in JAX's default float precision. It runs the
    rasteriser's own compiled function, so the tests check what renders."""
    dtype = jnp.result_type(float)
    d, width = np.broadcast_arrays(np.asarray(d, dtype), np.asarray(width, dtype))
    coverage = coverage_loop(np.dtype(dtype).name)
    return np.array([coverage(a, b) for a, b in zip(d.ravel(), width.ravel())], dtype).reshape(d.shape)


@dataclasses.dataclass(frozen=True)
class Fragments:
    """Pixels covered by segments, grouped by segment in input order.

    `pixel` (int32): row-major pixel index y·W + x; `segment` (int32): index into the input
    arrays, or that segment's entry of the raster's `labels` when it was given; floats are
    in JAX's default precision (float32, or float64 with x64 on);
    `coverage` ∈ (0, 1]; `t` ∈ [0, 1): screen-space position along the segment;
    `depth`: interpolated depth (perspective-correct for perspective views), or None when
    the raster was asked for none.
    """

    pixel: Arrays
    segment: Arrays
    coverage: Arrays
    t: Arrays
    depth: Arrays | None

    def take(self, index) -> Fragments:
        depth = None if self.depth is None else self.depth[index]
        return Fragments(self.pixel[index], self.segment[index], self.coverage[index], self.t[index], depth)

    @property
    def depths(self) -> Arrays:
        """`depth`, of a raster that interpolated it (ValueError otherwise)."""
        if self.depth is None:
            raise ValueError("this raster interpolated no depth (rasterize(..., depth=False))")
        return self.depth

    @property
    def size(self) -> int:
        return self.pixel.shape[0]


def rasterize(
    xy0: np.ndarray,
    xy1: np.ndarray,
    z0: np.ndarray,
    z1: np.ndarray,
    width: np.ndarray,
    image_width: int,
    image_height: int,
    perspective: bool,
    *,
    depth: bool = True,
    labels: np.ndarray | None = None,
) -> Fragments:
    """All (segment, pixel) pairs with positive coverage, segment after segment.

    **Arguments:** per segment `xy0`, `xy1` (`[E, 2]` pixel coordinates), depths `z0`, `z1`
    (`[E]`), ribbon `width` (`[E]` pixels, or `[E, 2]`: at each end, `ribbon_widths`); the
    raster size; whether depth is
    interpolated perspective-correctly (1/z linear in screen space) or linearly; `depth`:
    whether to interpolate it at all (the camera's fragments need it only for an
    occluder's depth test: without, `Fragments.depth` is None and the kernel skips it);
    `labels` (`[E]` int32, optional): what `Fragments.segment` holds for each segment
    instead of its index (the camera's fragments name their segment's first point: a
    pass over all fragments saved).

    Columns along each segment's major axis are laid out here in NumPy; the per-pixel
    maths runs in one compiled loop over their candidate rows (`raster_loop`), in JAX's
    default float precision (float64 when x64 is enabled), in pieces on every core
    (`rasterize_parts`) that are then moved together in place (`joined`).
    """
    args = (xy0, xy1, z0, z1, width, image_width, image_height, perspective)
    pieces = rasterize_parts(*args, depth=depth, labels=labels)
    return pieces[0] if len(pieces) == 1 else joined(pieces)


def joined(pieces: list[Fragments]) -> Fragments:
    """`rasterize_parts`' pieces (views of the same fields, in order) moved together in
    place: each piece after the first is shifted down to follow the one before, so no
    second set of fields is allocated. The pages a shifted piece leaves stay with the
    fields until they are freed."""
    shift = _shift_kernel()
    names = ("pixel", "segment", "coverage", "t") + (("depth",) if pieces[0].depth is not None else ())
    # The fields that the first piece starts (rasterize_parts writes it from their start).
    bases = {name: getattr(pieces[0], name).base for name in names}
    end = pieces[0].size
    for piece in pieces[1:]:
        for name in names:
            field, base = getattr(piece, name), bases[name]
            shift(base, (field.ctypes.data - base.ctypes.data) // base.itemsize, end, piece.size)
        end += piece.size
    joined = {name: bases[name][:end] for name in names}
    return Fragments(**joined) if "depth" in joined else Fragments(**joined, depth=None)


@functools.cache
def _shift_kernel():
    """A loop that moves `x[src : src + n]` to `x[dst : dst + n]`, dst ≤ src, front to
    back (safe where they overlap; NumPy would copy through a temporary)."""

    @compile_loop()
    @no_type_check
    def shift(x, src, dst, n):
        for k in range(n):
            x[dst + k] = x[src + k]

    return shift


def rasterize_parts(
    xy0: np.ndarray,
    xy1: np.ndarray,
    z0: np.ndarray,
    z1: np.ndarray,
    width: np.ndarray,
    image_width: int,
    image_height: int,
    perspective: bool,
    *,
    depth: bool = True,
    labels: np.ndarray | None = None,
    parts: int | None = None,
    seen: Callable[[int], tuple] | None = None,
) -> list[Fragments]:
    """`rasterize`'s fragments in `parts` pieces, rasterised at once on as many threads:
    each piece holds the fragments of a contiguous run of segments (about equal in
    candidates), so the pieces in order are `rasterize`'s fragments. Default: one per core
    (`host_threads`) from PARALLEL_MIN candidates on, else one.

    Each piece is written into its own share of fields sized for every candidate, and
    stays there: `group_parts` reads the camera's pieces as they are. (Copying them
    together into new fields had left a third region resident and made the camera raster
    at 100k strands / 1024² slower on two cores than on one, BENCHMARKS.md "rasterize";
    `rasterize` shifts them together in place instead.)"""
    plan = raster_plan(xy0, xy1, z0, z1, width, image_width, image_height)
    seg_data, lo, columns, rows = plan.seg_data, plan.lo, plan.columns, plan.rows
    n, dtype = columns.shape[0], seg_data.dtype
    # The covered candidates are written straight into one array per field, sized for
    # every candidate: pages never written are never resident, so the fields cost what they
    # hold (BENCHMARKS.md "Memory").
    # Each segment's first candidate in the fields; the last entry is their capacity.
    seg_start = np.concatenate([[0], np.cumsum(columns)]) * rows
    capacity = int(seg_start[-1])
    labels = np.arange(n, dtype=np.int32) if labels is None else np.asarray(labels, np.int32)
    if labels.shape != (n,):
        raise ValueError(f"labels must hold one entry per segment ({n}), got shape {labels.shape}")
    raster = functools.partial(
        raster_loop(np.dtype(dtype).name),
        seg_data,
        labels,
        lo,
        columns,
        rows,
        image_width,
        image_height,
        bool(perspective),
        depth,
    )
    if parts is None:
        parts = host_threads() if capacity >= PARALLEL_MIN else 1
    bounds = split_evenly(columns, parts)
    # Where each piece's share begins (the last: the fields' length), `check_memory`'s.
    counting = functools.partial(raster, EVERY_COVERED)
    starts = check_memory(counting, bounds, seg_start, np.dtype(dtype), depth, image_width, image_height)
    seen = seen or (lambda k: EVERY_COVERED)
    size = starts[-1]
    # `Fragments`' fields, in the order the loop writes them (`raster_loop`).
    fields = dict(
        pixel=np.empty(size, np.int32),
        segment=np.empty(size, np.int32),
        coverage=np.empty(size, dtype),
        t=np.empty(size, dtype),
        depth=np.empty(size if depth else 0, dtype),
    )
    shares = [
        {name: f[begin:end] if f.size else f for name, f in fields.items()}
        for begin, end in zip(starts[:-1], starts[1:])
    ]
    filled = in_parallel(
        [
            functools.partial(raster, seen(k), a, b, False, *share.values())
            for k, (a, b, share) in enumerate(zip(bounds[:-1], bounds[1:], shares))
        ]
    )
    return [_written(share, k, depth) for share, k in zip(shares, filled)]


def _written(share: dict[str, np.ndarray], k: int, depth: bool) -> Fragments:
    """The `k` fragments the loop wrote at the start of a piece's `share` of the fields
    (without `depth`, its empty field is none)."""
    return Fragments(
        pixel=share["pixel"][:k],
        segment=share["segment"][:k],
        coverage=share["coverage"][:k],
        t=share["t"][:k],
        depth=share["depth"][:k] if depth else None,
    )


def count_fragments(
    xy0, xy1, z0, z1, width, image_width: int, image_height: int, perspective: bool, *, limit: int
) -> int | None:
    """The number of fragments `rasterize` (the same arguments) would give, counted by its
    loop without writing them, on every core; None, without counting, where the loop would
    visit more than `limit` candidates in the image (the count would take as long as a
    raster of that many fragments). For the capacity estimate (`_estimate`)."""
    plan = raster_plan(xy0, xy1, z0, z1, width, image_width, image_height)
    x_major = plan.seg_data[:, 8] > 0
    across = np.where(x_major, image_height, image_width) + 3  # the rows the loop visits
    if int(np.sum(plan.columns * np.minimum(plan.rows, across))) > limit:
        return None
    n, dtype = plan.columns.shape[0], plan.seg_data.dtype
    raster = functools.partial(
        raster_loop(np.dtype(dtype).name),
        plan.seg_data,
        np.zeros(n, np.int32),
        plan.lo,
        plan.columns,
        plan.rows,
        image_width,
        image_height,
        bool(perspective),
        False,
        EVERY_COVERED,
    )
    ints, floats = np.empty(0, np.int32), np.empty(0, dtype)  # not written when counting
    bounds = split_evenly(plan.columns, host_threads())
    tasks = [
        functools.partial(raster, a, b, True, ints, ints, floats, floats, floats)
        for a, b in zip(bounds[:-1], bounds[1:])
    ]
    return sum(in_parallel(tasks))
