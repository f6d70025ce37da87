"""The abstract visibility ordering and its registry (docs/model.md §4, docs/architecture.md).

An ordering is a small immutable configuration (`[ordering]` in a scene file) that turns
the camera's depths of the drawable segments into a draw order, the first drawn first
(far to near for "over"). A new ordering is one module with a subclass registered by
`@register_ordering`.
"""

from __future__ import annotations

import abc
import dataclasses
from typing import Any, ClassVar

import numpy as np

from ..._errors import SceneError
from ..._registry import Registry

__all__ = ["AbstractOrdering", "register_ordering", "ordering_class", "ordering_names", "Ordering"]


@dataclasses.dataclass(frozen=True)
class AbstractOrdering(abc.ABC):
    """A visibility order. Subclasses set `method` (the scene-file name) and implement
    `order`; their dataclass fields are the `[ordering]` keys besides `method`."""

    method: ClassVar[str]

    @abc.abstractmethod
    def order(
        self, strands, segments: np.ndarray | None, seg_depth: np.ndarray, drawable: np.ndarray
    ) -> np.ndarray:
        """The draw order (`int64`, the first drawn first) of the segments whose indices
        are in `drawable` (both ends beyond the near plane), given every segment's
        camera depth `seg_depth` (`[E]`, the farther endpoint's, kim-2003 §3). An ordering
        by depth alone reads neither `strands` nor `segments` (`draw_order` passes None)."""


ORDERINGS: Registry[AbstractOrdering] = Registry("ordering", "method", "method")
register_ordering = ORDERINGS.register
ordering_names = ORDERINGS.names
ordering_class = ORDERINGS.get


def Ordering(method: str = "bins", *args: Any, **options: Any) -> AbstractOrdering:  # noqa: N802 (a factory named like the type it makes)
    """The registered ordering `method` with its options (its dataclass fields, in order or
    by name), e.g. `Ordering("bins", 64)`; `SceneError` for an unknown method or an
    option it does not take."""
    return ORDERINGS.make(method, *args, **options)


def check_count(name: str, value, lo: int, hi: int, hi_text: str | None = None) -> int:
    """`value` as an int in [lo, hi], or `SceneError` naming `name` (booleans refused)."""
    if isinstance(value, bool) or int(value) != value or not lo <= value <= hi:
        raise SceneError(f"{name} must be an integer in [{lo}, {hi_text or hi}], got {value!r}")
    return int(value)
