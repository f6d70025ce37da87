"""`method = "bins"`: kim-2003 §3's depth bins (docs/model.md §4)."""

from __future__ import annotations

import dataclasses

import numpy as np

from ._base import AbstractOrdering, check_count, register_ordering
from ._depth import bin_index

__all__ = ["DepthBins"]


@register_ordering
@dataclasses.dataclass(frozen=True)
class DepthBins(AbstractOrdering):
    """Far bins first, by index within a bin: an approximate sort in O(E)."""

    bins: int = 256
    method = "bins"

    def __post_init__(self):
        object.__setattr__(self, "bins", check_count("ordering.bins", self.bins, 1, 2**24, "2^24"))

    def order(self, strands, segments, seg_depth, drawable) -> np.ndarray:
        key = (self.bins - 1) - bin_index(seg_depth[drawable], self.bins)  # far bins first
        # Stable sort keeps index order within a bin; 16-bit keys take NumPy's radix sort.
        if self.bins <= 1 << 16:
            key = key.astype(np.uint16)
        return drawable[np.argsort(key, kind="stable").astype(np.int64)]
