"""The one cache of the renderer: per `Scene` object, what its geometry stage computed.

A scene's set-up (`_geometry_stage/_setup.prepare`), its geometry stage
(`_geometry_stage/_stage.geometry_stage` with the scene's own opacity) and the renderers'
disagreement band (`_disagreement`) depend on the scene alone, so they are kept per scene
object, under one name each, while the scene lives (a weak reference), and `forget(scene)`
drops all of them. Holding the
`Geometry` yourself (`geometry_stage(scene)`, then `shading_stage(geometry, params)`) is
the explicit alternative; a render with a given `order` is never cached.
"""

from __future__ import annotations

import weakref
from collections.abc import Callable
from typing import Any, TypeVar

__all__ = ["cached", "forget"]

T = TypeVar("T")

_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def cached(scene: Any, name: str, compute: Callable[[], T]) -> T:
    """`compute()` once per `scene` object and `name`; later calls return that value."""
    entries = _CACHE.setdefault(scene, {})
    if name not in entries:
        entries[name] = compute()
    return entries[name]


def forget(scene: Any) -> None:
    """Drop everything cached for `scene` (its set-up, geometry stage and band), so the
    next render runs every stage again (for timing a full render)."""
    _CACHE.pop(scene, None)
