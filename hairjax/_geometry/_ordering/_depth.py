"""The depth keys and sorts the orderings share (kim-2003 §3; docs/model.md §4): a
segment's depth, kim-2003's bin index and the roots' centre."""

from __future__ import annotations

import numpy as np

__all__ = ["bin_index", "hair_centre", "segment_depth"]


def segment_depth(depth: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """The depth of each segment's farther endpoint (kim-2003: "using the larger depth")."""
    return np.maximum(depth[segments[:, 0]], depth[segments[:, 1]])


def bin_index(depth: np.ndarray, bins: int) -> np.ndarray:
    """kim-2003 §3: i = ⌊N (D − Dmin) / (Dmax − Dmin + ε)⌋ with ε = (Dmax − Dmin) / (2N).

    ε < (Dmax − Dmin)/N as kim-2003 requires, and large enough that D = Dmax lands in bin
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


def hair_centre(points: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """The centre of the roots' bounding box (`[3]`): the "inside" of the hair (and the point
    the Scheuermann strand normal points away from, docs/model.md §17)."""
    roots = np.asarray(points, np.float64)[np.asarray(offsets)[:-1]]
    return 0.5 * (roots.min(axis=0) + roots.max(axis=0))
