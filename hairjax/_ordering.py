"""Visibility ordering of segments (kim-2003 §3): depth bins, exact sort, or none; and
the static inside-to-outside order of scheuermann-2004 slide 14, from the geometry alone.

Returns a draw order: segment indices, the first drawn first (farthest first).
"""

from __future__ import annotations

import numpy as np

__all__ = ["bin_index", "draw_order", "hair_centre", "segment_depth", "static_order"]


def segment_depth(depth: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """The depth of each segment's farther endpoint (kim-2003: "using the larger depth")."""
    return np.maximum(depth[segments[:, 0]], depth[segments[:, 1]])


def bin_index(depth: np.ndarray, bins: int) -> np.ndarray:
    """kim-2003 §3: i = ⌊N (D − Dmin) / (Dmax − Dmin + ε)⌋ with ε = (Dmax − Dmin) / (2N).

    ε < (Dmax − Dmin)/N as the seed requires, and large enough that D = Dmax lands in bin
    N − 1 (N·range/(range(1 + 1/2N)) < N). Returns `int64` in [0, N).
    """
    depth = np.asarray(depth, dtype=np.float64)
    if depth.size == 0:
        return np.zeros(0, dtype=np.int64)
    dmin, dmax = depth.min(), depth.max()
    span = dmax - dmin
    if not span > 0:
        # Fires when every segment is at one depth (Dmax = Dmin): one bin holds them all.
        return np.zeros(depth.shape, dtype=np.int64)
    eps = span / (2 * bins)
    i = np.floor(bins * (depth - dmin) / (span + eps)).astype(np.int64)
    # Fires only through rounding at D = Dmax when span + ε rounds to span (tiny spans).
    return np.minimum(i, bins - 1)


def draw_order(seg_depth: np.ndarray, method: str, bins: int = 256) -> np.ndarray:
    """Segment indices in drawing order: far bins first, by index within a bin (`bins`);
    by decreasing farther-endpoint depth, ties by index (`exact`); index order (`none`)."""
    n = seg_depth.shape[0]
    if method == "none":
        return np.arange(n, dtype=np.int64)
    if method == "exact":
        return np.argsort(-seg_depth, kind="stable").astype(np.int64)
    if method == "bins":
        key = (bins - 1) - bin_index(seg_depth, bins)  # far bins first
        # Stable sort keeps index order within a bin; 16-bit keys take NumPy's radix sort.
        if bins <= 1 << 16:
            key = key.astype(np.uint16)
        return np.argsort(key, kind="stable").astype(np.int64)
    raise ValueError(f"unknown ordering method {method!r}")


def hair_centre(points: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """The centre of the roots' bounding box (`[3]`): the "inside" of the hair (and the point
    the Scheuermann strand normal points away from, docs/model.md §17)."""
    roots = np.asarray(points, np.float64)[np.asarray(offsets)[:-1]]
    return 0.5 * (roots.min(axis=0) + roots.max(axis=0))


def static_order(points: np.ndarray, segments: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """scheuermann-2004 slide 14: a draw order computed once, from the geometry alone.

    Segments are drawn **inside to outside**: by increasing distance from `centre` of their
    endpoint nearer to it (the inside analogue of kim-2003's "larger depth"), ties by index.
    For a viewer outside the hair, what is farther inside is mostly behind, so "over" in this
    order approximates back to front from every side.

    **Arguments:** `points` `[P, 3]`, `segments` `[E, 2]` (point indices), `centre` `[3]`.
    **Returns:** `int64` `[E]`, a permutation of the segment indices, the first drawn first.
    """
    radius = np.linalg.norm(np.asarray(points, np.float64) - np.asarray(centre, np.float64), axis=1)
    key = np.minimum(radius[segments[:, 0]], radius[segments[:, 1]])
    return np.argsort(key, kind="stable").astype(np.int64)


def stable_argsort_uint32(keys: np.ndarray) -> np.ndarray:
    """Stable argsort of non-negative keys < 2^32: two passes of NumPy's 16-bit radix sort
    (least significant half first), O(n) instead of timsort's O(n log n)."""
    keys = np.asarray(keys)
    low = np.argsort((keys & 0xFFFF).astype(np.uint16), kind="stable")
    if keys.size == 0 or keys.max() < (1 << 16):
        return low
    high = np.argsort((keys[low] >> 16).astype(np.uint16), kind="stable")
    return low[high]
