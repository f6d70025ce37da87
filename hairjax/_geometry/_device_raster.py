"""The raster and the grouping by pixel as XLA programs, for the set-up on an accelerator
(docs/model.md §5, §6; docs/architecture.md "One GPU").

On the CPU the set-up rasterises and groups with loops compiled by numba (`_raster`,
`_group`): XLA's CPU backend has no fast stream compaction or stable sort, and its sort of
the 55 M fragment keys at 100k strands / 1024² alone outlasts the GL render there
(BENCHMARKS.md, "The device-resident set-up on this CPU"). On a GPU those are the
primitives XLA is fast at (4 ms for that sort on an H200), and the host loops plus the
fragments' trip to the device are most of a render. So where JAX's default device is not
the CPU, the set-up runs the same raster there:

- `device_candidates`: every candidate of the raster plan (`_raster_plan`: the same
  columns and rows the host loop visits) evaluated in one XLA program, in raster order
  (segment, column, row), with coverage 0 where the loop writes nothing;
- `rasterize_on_device`: `rasterize`'s fragments, the covered candidates in that order
  (the light's), kept as the hidden fragments' cut keeps its own (`keep_on_device`);
- `group_on_device`: the kept candidates sorted by pixel, stably, so that each pixel's
  run is in raster order, front to back: the host's counting sort, as one XLA sort.

Capacity policy: the plan's columns and segments are padded to the fragments' buckets
(`fragment_bucket`: a similar scene reuses the compiled program), a plan whose candidates
need more than the device's free memory is refused before anything is allocated
(`SceneTooLarge`), and the count of kept fragments is the one value read back.

Which kernels a set-up runs is its placement (`_placement`): "device" runs these, "host"
the loops; by default the device unless it is the CPU.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import lax

from .._constants import PIXEL_CENTRE
from .._errors import SceneTooLarge
from ._capacity import fragment_bucket
from ._coverage import coverage_formula
from ._hidden import keep_on_device
from ._host import available_memory
from ._raster import Fragments
from ._raster_plan import raster_plan

__all__ = [
    "device_memory",
    "candidate_size",
    "candidate_bytes",
    "device_candidates",
    "rasterize_on_device",
    "GroupedOnDevice",
    "group_on_device",
]


def _free_bytes() -> int | None:
    """Free memory of JAX's default device (the host's on the CPU), or None if unknown."""
    device = jax.devices()[0]
    if device.platform == "cpu":
        return available_memory()
    stats = device.memory_stats() or {}
    if "bytes_limit" not in stats:
        return None
    return int(stats["bytes_limit"]) - int(stats.get("bytes_in_use", 0))


def device_memory() -> int | None:
    """Free memory of JAX's default device (the host's on the CPU), or None if unknown."""
    return _free_bytes()


def candidate_size(dtype, depth: bool) -> int:
    """Bytes per candidate of `device_candidates`: its fields, and a sort key and index."""
    return 8 + (3 if depth else 2) * np.dtype(dtype).itemsize + 8


def candidate_bytes(plan, depth: bool) -> int:
    """Bytes `device_candidates` allocates for the raster `plan` (`_raster_plan`): every
    candidate of its columns, padded to their bucket."""
    c_pad = fragment_bucket(int(plan.columns.sum()) + 1)
    return c_pad * plan.rows * candidate_size(plan.seg_data.dtype, depth)


def device_candidates(
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
    """Every candidate of `rasterize`'s raster plan (the same arguments) on the default
    device (`[C]` each, raster order), as `Fragments` of JAX arrays: `coverage` is 0
    where the host loop writes nothing (outside the image, the segment's [0, L) or the
    ribbon, and the buckets' padding)."""
    plan = raster_plan(xy0, xy1, z0, z1, width, image_width, image_height)
    columns = plan.columns
    n, total = columns.size, int(columns.sum())
    labels = np.arange(n, dtype=np.int32) if labels is None else np.asarray(labels, np.int32)
    n_pad, c_pad = fragment_bucket(n + 1), fragment_bucket(total + 1)
    dtype = plan.seg_data.dtype
    need, per_candidate = candidate_bytes(plan, depth), candidate_size(dtype, depth)
    free = _free_bytes()
    if free is not None and need > free:
        raise SceneTooLarge(
            f"the {image_width}x{image_height} raster of this scene has {total * plan.rows:,} candidate "
            f"fragments, which need {need / 2**30:.1f} GiB ({per_candidate} bytes each) on the device; "
            f"{free / 2**30:.1f} GiB is free there: render fewer pixels (--size), fewer or thinner "
            "strands, or with the set-up on the host (placement='host', or HAIRJAX_SETUP=host)"
        )
    seg_data = np.zeros((n_pad, plan.seg_data.shape[1]), dtype)
    seg_data[:n] = plan.seg_data  # padding rows: length 0, no candidate covered
    # The padding columns belong to the first padding segment (row n), so that the
    # columns' segments are a repeat of exactly c_pad entries.
    counts = np.zeros(n_pad, np.int32)
    counts[:n] = columns
    counts[n] = c_pad - total
    lo = np.zeros(n_pad, np.int32)
    lo[:n] = plan.lo
    label = np.zeros(n_pad, np.int32)
    label[:n] = labels
    fields = _candidates(
        seg_data, counts, lo, label, c_pad, plan.rows, image_width, image_height, bool(perspective), depth
    )
    return Fragments(**fields)


@functools.partial(jax.jit, static_argnums=(4, 5, 6, 7, 8, 9))
def _candidates(
    seg_data, counts, lo, label, n_columns, rows, image_width, image_height, perspective, with_depth
):
    """`Fragments`' fields (pixel, segment label, coverage, t, depth or None) of every
    candidate, `[n_columns·rows]` each.

    The same arithmetic, in the same order and precision, as the host loop
    (`_raster_loop`), the coverage by the same formula (`coverage_formula`), so the two
    write the same fragments (up to where each compiler contracts a multiply-add: tested)."""
    dtype = seg_data.dtype
    seg = jnp.repeat(jnp.arange(counts.shape[0], dtype=jnp.int32), counts, total_repeat_length=n_columns)
    first_column = jnp.cumsum(counts) - counts
    c = seg_data[seg]
    x0, y0, dx, dy, length, w0, za, zb, xm, reach, w1 = (c[:, i, None] for i in range(11))
    # Column k (exact in float32: < 2^24) of its segment's major axis.
    k = (lo[seg] + (jnp.arange(n_columns, dtype=jnp.int32) - first_column[seg])).astype(dtype)[:, None]
    x_major = xm > 0
    da = jnp.where(x_major, dx, dy)
    # Fires only on padding rows (length 0): a segment with columns has |da| ≥ L/√2 > 0.
    da = jnp.where(da != 0, da, 1.0)
    length_safe = jnp.where(length > 0, length, 1.0)  # fires likewise, on padding only
    inv_len = 1.0 / length_safe
    slope = jnp.where(x_major, dy, dx) / da
    offset = reach * length / jnp.abs(da)
    b_line = jnp.where(x_major, y0, x0) + (k + PIXEL_CENTRE - jnp.where(x_major, x0, y0)) * slope
    m = jnp.floor(b_line - offset - PIXEL_CENTRE) + 1.0 + jnp.arange(rows, dtype=dtype)[None, :]
    px = jnp.where(x_major, k, m)
    py = jnp.where(x_major, m, k)
    rx = px + PIXEL_CENTRE - x0
    ry = py + PIXEL_CENTRE - y0
    s = (rx * dx + ry * dy) * inv_len
    t = s * inv_len
    coverage = coverage_formula(dtype.type, jnp.minimum, jnp.maximum)
    # w₀ + t(w₁ − w₀) is exactly w₀ for ribbons of constant width (pixel widths).
    cov = coverage(jnp.abs(rx * dy - ry * dx) * inv_len, w0 + t * (w1 - w0))
    inside = (px >= 0) & (px < image_width) & (py >= 0) & (py < image_height)
    # Padding rows have length 0 and fail s < L.
    cov = jnp.where(inside & (s >= 0) & (s < length), cov, 0.0)
    pixel = py.astype(jnp.int32) * image_width + px.astype(jnp.int32)
    segment = jnp.broadcast_to(label[seg][:, None], pixel.shape)
    fields = dict(pixel=pixel, segment=segment, coverage=cov, t=t, depth=None)
    if with_depth:
        if perspective:
            # Fire only on padding rows (depth 0): drawn segments lie beyond the near plane.
            za_safe, zb_safe = jnp.where(za != 0, za, 1.0), jnp.where(zb != 0, zb, 1.0)
            z = 1.0 / ((1.0 - t) / za_safe + t / zb_safe)
        else:
            z = za + t * (zb - za)
        # Fires for segments at constant depth: keep z exactly (no self-shadowing by a
        # rounding error in 1/(1/z)).
        fields["depth"] = jnp.where(za == zb, za, z)
    return {name: None if f is None else f.ravel() for name, f in fields.items()}


def rasterize_on_device(*args, **kwargs) -> Fragments:
    """`rasterize` (the same arguments) on the default device: the covered candidates of
    `device_candidates`, in raster order. One value read back: their count."""
    candidates = device_candidates(*args, **kwargs)
    covered = candidates.coverage > 0
    fields = (candidates.pixel, candidates.segment, candidates.coverage, candidates.t)
    if candidates.depth is None:
        pixel, segment, coverage, t = keep_on_device(covered, *fields)
        return Fragments(pixel, segment, coverage, t, None)
    pixel, segment, coverage, t, depth = keep_on_device(covered, *fields, candidates.depth)
    return Fragments(pixel, segment, coverage, t, depth)


class GroupedOnDevice(NamedTuple):
    """Entries grouped by pixel on the device, as `_group.Grouped` on the host: `pixel`
    ascending, `fields` permuted alike, and the number of entries `kept` (F, read back)."""

    pixel: jax.Array
    fields: tuple[jax.Array, ...]
    kept: int


def group_on_device(
    pixel: jax.Array, keep: jax.Array, n_pixels: int, *fields: jax.Array, capacity=None
) -> GroupedOnDevice:
    """The entries where `keep` is set, grouped by `pixel` in their given order, on the
    device (`GroupedOnDevice`), as `group_by_pixel` gives on the host. One value read
    back: F. `capacity` (optional): a function of F giving the arrays' length
    (`fragment_bucket`); entries from F on are then padding, pixel `n_pixels` and fields
    0. Without it the arrays hold the F entries.

    The kept entries are gathered first, so the sort reads only them: the candidates'
    uncovered, occluded and hidden ones are never sorted."""
    count = int(jnp.count_nonzero(keep))
    size = count if capacity is None else capacity(count)
    if pixel.shape[0] == 0:  # no entry to gather from: padding only
        zeros = tuple(jnp.zeros(size, f.dtype) for f in fields)
        return GroupedOnDevice(jnp.full(size, n_pixels, pixel.dtype), zeros, 0)
    index = jnp.nonzero(keep, size=size, fill_value=0)[0]
    key, index = _sorted_by_pixel(pixel, index, count, n_pixels)
    real = jnp.arange(size) < count
    grouped = tuple(jnp.where(real, jnp.take(f, index, mode="clip"), 0) for f in fields)  # clip: in range
    return GroupedOnDevice(key, grouped, count)


@functools.partial(jax.jit, static_argnums=3)
def _sorted_by_pixel(pixel, index, count, n_pixels):
    """The pixels of the entries at `index` (the kept ones in order, then padding from
    `count` on, keyed past the last pixel) ascending, stably, and their entries."""
    key = jnp.where(jnp.arange(index.shape[0]) < count, pixel[index], n_pixels)
    return lax.sort((key, index), num_keys=1, is_stable=True)
