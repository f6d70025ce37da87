"""`method = "static"`: scheuermann-2004 slide 14's inside-to-outside order, from the
geometry alone (docs/model.md §4)."""

from __future__ import annotations

import dataclasses

import numpy as np

from ._base import AbstractOrdering, register_ordering
from ._depth import hair_centre

__all__ = ["StaticOrder", "static_order"]


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


@register_ordering
@dataclasses.dataclass(frozen=True)
class StaticOrder(AbstractOrdering):
    """The same order for every view (no depths needed): `static_order` about the roots'
    centre, the segments not drawable from this camera left out."""

    method = "static"

    def order(self, strands, segments, seg_depth, drawable) -> np.ndarray:
        order = static_order(strands.points, segments, hair_centre(strands.points, strands.offsets))
        mask = np.zeros(len(segments), bool)
        mask[drawable] = True
        return order[mask[order]]
