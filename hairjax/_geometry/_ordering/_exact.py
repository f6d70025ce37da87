"""`method = "exact"`: a full depth sort, the reference order (docs/model.md §4)."""

from __future__ import annotations

import dataclasses

import numpy as np

from ._base import AbstractOrdering, register_ordering

__all__ = ["ExactOrder"]


@register_ordering
@dataclasses.dataclass(frozen=True)
class ExactOrder(AbstractOrdering):
    """By decreasing farther-endpoint depth, ties by index (a stable sort)."""

    method = "exact"

    def order(self, strands, segments, seg_depth, drawable) -> np.ndarray:
        depth = seg_depth[drawable]
        return drawable[np.argsort(-depth, kind="stable").astype(np.int64)]
