"""Visibility orderings (docs/model.md §4): one module each, registered by method name.

`none` (index order), `bins` (kim-2003 §3's depth bins), `exact` (a full sort), `static`
(scheuermann-2004 slide 14's inside-to-outside order).
"""

import numpy as np

from ._base import AbstractOrdering as AbstractOrdering
from ._base import Ordering as Ordering
from ._base import ordering_class as ordering_class
from ._base import ordering_names as ordering_names
from ._base import register_ordering as register_ordering
from ._bins import DepthBins as DepthBins
from ._depth import bin_index as bin_index
from ._depth import hair_centre as hair_centre
from ._depth import segment_depth as segment_depth
from ._exact import ExactOrder as ExactOrder
from ._none import IndexOrder as IndexOrder
from ._static import StaticOrder as StaticOrder
from ._static import static_order as static_order


def draw_order(seg_depth: np.ndarray, ordering: AbstractOrdering | str, *options) -> np.ndarray:
    """Indices of all segments in drawing order for segment depths `seg_depth` (`[E]`),
    under a depth-based `ordering`: an object (`Ordering("bins", 64)`) or a registered
    method's name and its options (`draw_order(d, "bins", 64)`, `draw_order(d, "exact")`)."""
    if isinstance(ordering, str):
        ordering = Ordering(ordering, *options)
    return ordering.order(None, None, seg_depth, np.arange(len(seg_depth), dtype=np.int64))
