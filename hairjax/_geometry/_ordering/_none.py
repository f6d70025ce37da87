"""`method = "none"`: segments in index order, no sort (docs/model.md §4)."""

from __future__ import annotations

import dataclasses

import numpy as np

from ._base import AbstractOrdering, register_ordering

__all__ = ["IndexOrder"]


@register_ordering
@dataclasses.dataclass(frozen=True)
class IndexOrder(AbstractOrdering):
    """The strands' own order: what a renderer without sorting draws."""

    method = "none"

    def order(self, strands, segments, seg_depth, drawable) -> np.ndarray:
        return np.asarray(drawable, dtype=np.int64)
