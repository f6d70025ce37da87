"""The sweep's knobs (docs/results.md): each a setter from (scene, value) to the scene to
render and its supersampling factor, and the exact reference they are measured against."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

from .._geometry._ordering import Ordering
from .._geometry._shadows import Shadows
from .._scene._scene import Scene

__all__ = ["KNOBS", "QUICK_KNOBS", "SHADOW_KNOBS", "SweepError", "knob_scene", "reference_scene"]


class SweepError(ValueError):
    """Bad sweep input, or an output folder that holds a different sweep."""


KNOBS: dict[str, tuple] = {
    "maps": (1, 2, 4, 8, 16, 32, 64, 128, 256, 512),
    "map_resolution": (64, 128, 256, 512, 1024, 2048),
    "bins": (1, 4, 16, 64, 256, 1024, 4096, "exact"),
    "width": (0.25, 0.5, 1.0, 2.0, 4.0),
    "supersampling": (1, 2, 3, 4),
}
# A few values per knob, for a smoke test and the notebook's test run.
QUICK_KNOBS: dict[str, tuple] = {
    "maps": (1, 4, 16),
    "map_resolution": (32, 64),
    "bins": (1, 16, "exact"),
    "width": (0.5, 1.0, 2.0),
    "supersampling": (1, 2),
}
SHADOW_KNOBS = ("maps", "map_resolution")


def _with_width(scene: Scene, factor: float) -> Scene:
    """Ribbons `factor` times as wide and as much more transparent (the same hair mass)."""
    strands = scene.strands
    return scene.replace(
        strands=strands.replace(width=strands.width * factor, alpha=np.minimum(strands.alpha / factor, 1.0))
    )


# Each knob: (scene, value) → (scene, supersampling factor). A `bins` value is a bin
# count, or the name of a registered ordering (e.g. "exact") to draw with instead.
def _with_shadow_option(scene: Scene, key: str, value: int) -> Scene:
    """Through the registry: a shadow method without the option is a SceneError naming it."""
    options = {**dataclasses.asdict(scene.shadows), key: int(value)}
    return scene.replace(shadows=Shadows(scene.shadows.method, **options))


_KNOB_SETTERS: dict[str, Callable] = {
    "maps": lambda s, v: (_with_shadow_option(s, "maps", v), 1),
    "map_resolution": lambda s, v: (_with_shadow_option(s, "resolution", v), 1),
    "bins": lambda s, v: (
        s.replace(ordering=Ordering(v) if isinstance(v, str) else Ordering("bins", int(v))),
        1,
    ),
    "width": lambda s, v: (_with_width(s, float(v)), 1),
    "supersampling": lambda s, v: (s, int(v)),
}


def knob_scene(scene: Scene, knob: str, value) -> tuple[Scene, int]:
    """The scene with one knob set, and the supersampling factor to render it with."""
    if knob not in _KNOB_SETTERS:
        raise SweepError(f"unknown knob {knob!r}; knobs: {', '.join(KNOBS)}")
    return _KNOB_SETTERS[knob](scene, value)


def reference_scene(scene: Scene, knobs: dict) -> tuple[Scene, int]:
    """Exact shadows (when the scene has shadows) at the scene's map resolution, exact
    ordering, the finest supersampling swept.

    The resolution stays the scene's: ribbons are w texels wide in the light's view
    (docs/model.md §7), so a finer map draws thinner hair and Ω does not converge as the
    resolution grows; the `map_resolution` knob shows how far it moves instead."""
    shadows = Shadows("exact", resolution=scene.shadows.resolution) if scene.shadows.casts else scene.shadows
    s = max(knobs.get("supersampling", (1,)))
    return scene.replace(shadows=shadows, ordering=Ordering("exact")), int(s)
