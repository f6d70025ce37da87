"""The set-up's camera fragments (docs/model.md §5, §6, §13): the ribbons rasterised
nearest segment first, the occluder's depth test (kim-2003 §3: depth test on, hair does
not write depth) and, for a render, the hidden fragments' cut (`_seen`), both as the
fragments are made, and the stable grouping by pixel that leaves each pixel's fragments
front to back, padded to the fragments' bucket (`fragment_bucket`) so that the geometry
stage's programs compile once per bucket.

Where they run is the set-up's placement (`_placement`): on the host, the compiled loops
(`rasterize_parts`, `group_parts`); on a device, the same raster and grouping as XLA
programs (`device_candidates`, `group_on_device`). Both give the same fragments, bit for
bit (tests/geometry/test_device_raster.py).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from .._geometry._capacity import fragment_bucket
from .._geometry._device_raster import device_candidates, group_on_device
from .._geometry._group import group_parts
from .._geometry._host import release_heap
from .._geometry._placement import Placement
from .._geometry._raster import Arrays, count_fragments
from .._geometry._raster_plan import RibbonRaster
from .._geometry._seen import Seen, rasterize_seen, seen_on_device

__all__ = ["PaddedFragments", "CameraFragments", "camera_fragments"]


class PaddedFragments(NamedTuple):
    """The camera's fragments grouped by pixel, front to back within a pixel, padded to
    `fragment_bucket(F)` entries (NumPy on the host, JAX arrays on a device)."""

    pixel: Arrays  # ascending; padding: H·W, past every pixel
    i0: Arrays  # first point of the fragment's segment (the second is i0 + 1); padding 0
    coverage: Arrays  # padding 0
    t: Arrays  # screen-space position along the segment; padding 0


@dataclasses.dataclass(frozen=True)
class CameraFragments:
    """`padded`, of which the first `count` entries are fragments; `drawn`: whether the
    raster covered any pixel before the occluder's depth test; `hidden`: each pixel's
    product of the (1 − α) of the hidden fragments left out (`[H·W]`, None when none
    were cut: `_seen`)."""

    padded: PaddedFragments
    count: int
    drawn: bool
    hidden: Arrays | None = None


def camera_fragments(
    raster: RibbonRaster, labels: np.ndarray, seen: Seen, placement: Placement, lap: Callable[[str], None]
) -> CameraFragments:
    """The camera's fragments of `raster`, each naming its entry of `labels` (`[E]`
    int32: its segment's first point), without those `seen` leaves out (`Seen`: behind
    the occluder's depth at their pixel centre, or hidden behind nearer fragments),
    grouped on the host or on the device as `placement` says. `lap(name)` times each
    step."""
    place = _on_device if placement == "device" else _on_host
    return place(raster, labels, seen, lap)


def _on_host(raster, labels, seen, lap):
    """By the host's compiled loops: the raster in pieces, one per core, the occluded and
    hidden fragments left out as they are met (`rasterize_seen`), read where they are by
    the counting sort (`group_parts`), into aligned arrays that the geometry stage shares
    with JAX (`_host`)."""
    pieces, hidden = rasterize_seen(raster, labels, seen)
    count = sum(piece.size for piece in pieces)
    lap("rasterize")
    grouped = group_parts(
        [(piece.pixel, piece.segment, piece.coverage, piece.t) for piece in pieces],
        raster.pixels,
        fragment_bucket(count),
    )
    del pieces
    release_heap(count * 16)  # the raster's 4 fields, handed back to the system
    lap("sort fragments")
    i0, coverage, t = grouped.fields
    padded = PaddedFragments(pixel=grouped.pixel, i0=i0, coverage=coverage, t=t)
    return CameraFragments(padded=padded, count=count, drawn=count > 0 or _covers_any(raster), hidden=hidden)


def _on_device(raster, labels, seen, lap):
    """As XLA programs on JAX's default device (`_device_raster`): every candidate of the
    same raster plan, the occluded and hidden ones marked (`seen_on_device`), then one
    stable sort by pixel of those left. JAX arrays."""
    candidates = device_candidates(**raster._asdict(), depth=seen.hit is not None, labels=labels)
    keep = candidates.coverage > 0
    jax.block_until_ready(keep)  # the lap times the raster, not its dispatch
    lap("rasterize")
    covered = keep
    if seen.hit is not None:
        keep &= _in_front(candidates, seen.hit)
    hidden = None
    if seen.opacity is not None:
        keep, hidden = seen_on_device(
            candidates.pixel,
            keep,
            candidates.segment,
            candidates.coverage,
            seen.opacity,
            seen.cutoff,
            raster.pixels,
        )
    grouped = group_on_device(
        candidates.pixel,
        keep,
        raster.pixels,
        candidates.segment,
        candidates.coverage,
        candidates.t,
        capacity=fragment_bucket,
    )
    lap("sort fragments")
    # Covered before the depth test: read back only when nothing is left after it.
    drawn = grouped.kept > 0 or bool(jnp.any(covered))
    i0, coverage, t = grouped.fields
    padded = PaddedFragments(pixel=grouped.pixel, i0=i0, coverage=coverage, t=t)
    return CameraFragments(padded=padded, count=grouped.kept, drawn=drawn, hidden=hidden)


def _covers_any(raster: RibbonRaster) -> bool:
    """Whether `raster` covers any pixel: counted (writing nothing) where the occluder or
    the cut left no fragment, for `CameraFragments.drawn`."""
    return bool(count_fragments(*raster, limit=np.iinfo(np.int64).max))


def _in_front(candidates, hit_depth):
    """Whether each of the device's `candidates` (`Fragments`) lies nearer than the
    occluder's `hit_depth` at its pixel, d < h, tested as the host tests it (in float64)
    although d is in the fragments' precision."""
    dtype = candidates.depths.dtype
    # d < h for a float64 h is d < h↑, h rounded up to the next float of d's type, so
    # the test in that type is the host's (which compares in float64).
    bound = hit_depth.astype(dtype)
    bound = np.where(bound < hit_depth, np.nextafter(bound, np.inf, dtype=dtype), bound)
    # clip: an uncovered candidate's pixel may lie outside the image; it is dropped anyway.
    return candidates.depths < jnp.asarray(bound)[jnp.clip(candidates.pixel, 0, bound.size - 1)]
