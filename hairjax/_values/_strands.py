"""Hair strands: ragged polylines stored flat, with per-strand opacity and width.

Strands are geometry, so they live in NumPy (float64) and are validated once, here.
The renderer casts to its working dtype; JAX sees only what the geometry stage derives.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from jaxtyping import ArrayLike

from .._constants import COORDINATE_BOUND

__all__ = [
    "Strands",
    "WIDTH_UNITS",
    "tangents",
    "unit_rows",
    "ArrayInput",
    "distinct_strands",
    "select_strands",
    "first_outside",
]

# What `np.asarray` reads: an array (NumPy or JAX), a number, or a (nested) list or tuple.
# (numpy.typing.ArrayLike means the same, but beartype, the tests' run-time checker, takes
# neither an int nor a float for the `complex` in it.)
ArrayInput = ArrayLike | Sequence[Any]

WIDTH_UNITS = ("pixels", "world")


@dataclasses.dataclass(frozen=True, eq=False)
class Strands:
    """A set of hair strands (polylines of possibly different point counts).

    **Fields:**

    - `points`: `float64[P, 3]`, all points, strand after strand; every coordinate finite
      and within ±`COORDINATE_BOUND` (1e18, hairjax/_constants.py: float32 squares of
      distances stay finite).
    - `offsets`: `int64[S + 1]`; strand `s` is `points[offsets[s]:offsets[s + 1]]`.
      Every strand has at least one point.
    - `alpha`: `float64[S]`, opacity a ∈ (0, 1] per strand.
    - `width`: `float64[S]`, ribbon width per strand (> 0), in `width_units`.
    - `width_units`: `"pixels"` (default: the ribbon is `width` pixels wide in every view)
      or `"world"` (`width` world units: w·f/D pixels at depth D, docs/model.md §5).
    - `color`: optional `float64[P, 3]` per-point colour, linear RGB, finite and ≥ 0
      (multiplies the diffuse and ambient terms, docs/model.md §1, §8; above 1 is allowed).
    - `attributes`: other arrays a file carried, by name (e.g. `"thickness"`,
      `"transparency"`, `"strand_uv"`); kept for `hairjax info`, not used for shading.
    """

    points: np.ndarray
    offsets: np.ndarray
    alpha: np.ndarray
    width: np.ndarray
    color: np.ndarray | None = None
    attributes: Mapping[str, np.ndarray] = dataclasses.field(default_factory=dict)
    width_units: str = "pixels"

    def __init__(
        self,
        points: ArrayInput,
        offsets: ArrayInput,
        alpha: ArrayInput,
        width: ArrayInput,
        color: ArrayInput | None = None,
        attributes: Mapping[str, np.ndarray] | None = None,
        width_units: str = "pixels",
    ):
        # Written out (not the dataclass's): it takes array-likes (a number broadcasts to
        # every strand) and stores the float64/int64 arrays the fields name.
        if width_units not in WIDTH_UNITS:
            raise ValueError(f"width_units must be one of {WIDTH_UNITS}, got {width_units!r}")
        points = np.asarray(points, dtype=np.float64)
        offsets = np.asarray(offsets, dtype=np.int64)
        if points.ndim != 2 or points.shape[1] != 3:
            raise ValueError(f"points must have shape [P, 3], got {points.shape}")
        _check_points(points)
        if offsets.ndim != 1 or offsets.size < 1 or offsets[0] != 0 or offsets[-1] != len(points):
            raise ValueError("offsets must be [0, ..., P] with one entry per strand plus one")
        if np.any(np.diff(offsets) < 1):
            raise ValueError("every strand needs at least one point")
        n = offsets.size - 1
        alpha = np.broadcast_to(np.asarray(alpha, dtype=np.float64), (n,)).copy()
        width = np.broadcast_to(np.asarray(width, dtype=np.float64), (n,)).copy()
        if not np.all((alpha > 0) & (alpha <= 1)):
            raise ValueError("alpha must lie in (0, 1]")
        if not np.all((width > 0) & np.isfinite(width)):
            raise ValueError("width must be positive and finite")
        if color is not None:
            color = np.broadcast_to(np.asarray(color, dtype=np.float64), points.shape).copy()
            bad = first_outside(color, lo=0.0)
            if bad is not None:
                raise ValueError(
                    f"the colour of point {bad} is {_vector(color[bad])}: colours are linear RGB, "
                    "finite and ≥ 0"
                )
        for name, value in (
            ("points", points),
            ("offsets", offsets),
            ("alpha", alpha),
            ("width", width),
            ("color", color),
        ):
            if value is not None:
                value.setflags(write=False)
            object.__setattr__(self, name, value)
        object.__setattr__(self, "attributes", dict(attributes or {}))
        object.__setattr__(self, "width_units", width_units)

    @classmethod
    def from_list(cls, strands, alpha=1.0, width=1.0, color=None) -> Strands:
        """Build from a list of `[n_i, 3]` arrays."""
        strands = [np.asarray(s, dtype=np.float64).reshape(-1, 3) for s in strands]
        offsets = np.concatenate([[0], np.cumsum([len(s) for s in strands])])
        points = np.concatenate(strands) if strands else np.zeros((0, 3))
        return cls(points, offsets, alpha, width, color)

    @property
    def num_strands(self) -> int:
        return self.offsets.size - 1

    @property
    def num_points(self) -> int:
        return self.points.shape[0]

    @property
    def strand_of_point(self) -> np.ndarray:
        """`int64[P]`: the strand each point belongs to."""
        return np.repeat(np.arange(self.num_strands), np.diff(self.offsets))

    def segments(self) -> np.ndarray:
        """`int64[E, 2]`: point indices of every segment (consecutive points of a strand)."""
        is_last = np.zeros(self.num_points, dtype=bool)
        is_last[self.offsets[1:] - 1] = True
        first = np.flatnonzero(~is_last)
        return np.stack([first, first + 1], axis=1)

    def replace(self, **changes) -> Strands:
        return dataclasses.replace(self, **changes)

    def transformed(self, scale: float = 1.0, translate=(0.0, 0.0, 0.0)) -> Strands:
        """Points scaled about the origin, then translated."""
        return self.replace(points=self.points * scale + np.asarray(translate, dtype=np.float64))


def _vector(v) -> str:
    return "(" + ", ".join(f"{x:.6g}" for x in v) + ")"


def first_outside(values, lo: float = -np.inf, hi: float = np.inf, lo_open: bool = False) -> int | None:
    """The index of the first item (row, for a 2-D array) of `values` with a value that is
    not finite or lies outside [lo, hi] ((lo, hi] with `lo_open`), or None when all lie in."""
    values = np.asarray(values, dtype=np.float64)
    # Comparisons with NaN are False, so NaN counts as outside; ±inf fails isfinite.
    inside = np.isfinite(values) & (values > lo if lo_open else values >= lo) & (values <= hi)
    if values.ndim > 1:
        inside = inside.all(axis=tuple(range(1, values.ndim)))
    bad = np.flatnonzero(~inside)
    return int(bad[0]) if bad.size else None


def _check_points(points: np.ndarray) -> None:
    bad = first_outside(points)
    if bad is not None:
        raise ValueError(f"point {bad} has a NaN or infinite coordinate: {_vector(points[bad])}")
    bad = first_outside(points, -COORDINATE_BOUND, COORDINATE_BOUND)
    if bad is not None:
        raise ValueError(
            f"point {bad} = {_vector(points[bad])} lies beyond ±{COORDINATE_BOUND:g}, the bound on "
            "coordinates that keeps the float32 projection finite (scale the hair down)"
        )


def distinct_strands(strands: Strands) -> np.ndarray:
    """`bool[S]`: the strands with two distinct points, i.e. at least one segment of nonzero
    length; the others (one point, or every point the same) draw nothing (docs/model.md §1)."""
    points, offsets = strands.points, strands.offsets
    if strands.num_strands == 0:
        return np.zeros(0, dtype=bool)
    # moves[k]: point k + 1 differs from point k, and both are in one strand.
    moves = np.append(np.any(points[1:] != points[:-1], axis=1), False)
    moves[offsets[1:] - 1] = False  # a strand's last point is not joined to the next strand's first
    return np.add.reduceat(moves.astype(np.int64), offsets[:-1]) > 0


def select_strands(strands: Strands, keep) -> Strands:
    """The strands where `keep` (`bool[S]`) is true, with their points, colours and the
    attributes that have one row per point or per strand (others are kept whole)."""
    keep = np.asarray(keep, dtype=bool)
    counts = np.diff(strands.offsets)
    point_keep = np.repeat(keep, counts)
    offsets = np.concatenate([[0], np.cumsum(counts[keep])])
    attributes = {}
    for name, value in strands.attributes.items():
        value = np.asarray(value)
        if value.ndim and len(value) == strands.num_points:
            value = value[point_keep]
        elif value.ndim and len(value) == strands.num_strands:
            value = value[keep]
        attributes[name] = value
    color = None if strands.color is None else strands.color[point_keep]
    return Strands(
        strands.points[point_keep],
        offsets,
        strands.alpha[keep],
        strands.width[keep],
        color,
        attributes,
        strands.width_units,
    )


def tangents(points: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Unit tangents: central differences, one-sided at strand ends (`float64[P, 3]`).

    Zero where the difference is zero (repeated points, one-point strands): such a point
    reflects ambient light only (docs/model.md §1).
    """
    prev = np.arange(len(points)) - 1
    nxt = np.arange(len(points)) + 1
    starts, ends = offsets[:-1], offsets[1:] - 1
    prev[starts] = starts
    nxt[ends] = ends
    # unit_rows gives 0 for repeated points and one-point strands: the tangent does not exist.
    return unit_rows(points[nxt] - points[prev])


def unit_rows(v: np.ndarray) -> np.ndarray:
    """Each row of `v` over its length; 0 for a zero row."""
    norm = np.linalg.norm(v, axis=-1, keepdims=True)
    # Fires for zero vectors (a repeated point's tangent, a point light or the eye at a
    # strand point): no direction, so no light.
    return np.where(norm > 0, v / np.where(norm > 0, norm, 1.0), 0.0)
