"""The sweep's knobs (docs/results.md): each a setter from (scene, value) to the scene to
render and its supersampling factor, and the exact reference they are measured against."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping

import numpy as np

from .._geometry._ordering import Ordering
from .._geometry._shadows import Shadows, shadow_method_class, shadow_method_names
from .._scene._scene import Scene

__all__ = [
    "KNOBS",
    "QUICK_KNOBS",
    "JOINT_KNOBS",
    "QUICK_JOINT_KNOBS",
    "SHADOW_KNOBS",
    "SHADOW_OPTIONS",
    "SweepError",
    "knob_scene",
    "method_options",
    "reference_scene",
    "reference_config",
    "settings_scene",
]


class SweepError(ValueError):
    """Bad sweep input, or an output folder that holds a different sweep."""


# The knobs that set a field of the shadow method (its `[shadows]` key, docs/model.md §7):
# knob → field. A method has the knob when its class has the field, so a method registered
# with a `layers` field (deep opacity maps) is swept in `layers` with no change here.
SHADOW_OPTIONS: dict[str, str] = {"maps": "maps", "map_resolution": "resolution", "layers": "layers"}


def _methods() -> tuple[str, ...]:
    """Every registered shadow method, those casting no shadows first (the cheapest)."""
    return tuple(sorted(shadow_method_names(), key=lambda name: shadow_method_class(name).casts))


KNOBS: dict[str, tuple] = {
    "maps": (1, 2, 4, 8, 16, 32, 64, 128, 256, 512),
    "map_resolution": (64, 128, 256, 512, 1024, 2048),
    "layers": (2, 4, 8, 16),
    "bins": (1, 4, 16, 64, 256, 1024, 4096, "exact"),
    "width": (0.25, 0.5, 1.0, 2.0, 4.0),
    "supersampling": (1, 2, 3, 4),
    "shadows": _methods(),
}
# A few values per knob, for a smoke test and the notebook's test run.
QUICK_KNOBS: dict[str, tuple] = {
    "maps": (1, 4, 16),
    "map_resolution": (32, 64),
    "layers": (2, 4),
    "bins": (1, 16, "exact"),
    "width": (0.5, 1.0, 2.0),
    "supersampling": (1, 2),
    "shadows": _methods(),
}
# The joint search's values (docs/results.md, "Joint search"): coarser than the sweep's
# (maps and bins in steps of 4, the raster one step either side of the default 256, no
# 1 or 2 maps, which the sweep shows to be an order of magnitude off), since it evaluates
# combinations; pass KNOBS to search those.
JOINT_KNOBS: dict[str, tuple] = {
    "shadows": _methods(),
    "maps": (4, 16, 64, 256),
    "map_resolution": (128, 256, 512),
    "layers": (2, 4, 8),
    "bins": (4, 16, 64, 256, "exact"),
    "width": (0.5, 1.0, 2.0),
    "supersampling": (1, 2, 3, 4),
}
# A tiny space, for a smoke run and the test suite's run of experiments/09_results.py.
QUICK_JOINT_KNOBS: dict[str, tuple] = {
    "shadows": _methods(),
    "maps": (4, 16),
    "layers": (2, 4),
    "bins": (16, "exact"),
    "supersampling": (1, 2),
}
# The knobs that mean nothing for a scene without shadows.
SHADOW_KNOBS = (*SHADOW_OPTIONS, "shadows")


def method_options(method: str) -> tuple[str, ...]:
    """The knobs of `SHADOW_OPTIONS` that the registered shadow method `method` takes."""
    fields = {f.name for f in dataclasses.fields(shadow_method_class(method))}
    return tuple(knob for knob, field in SHADOW_OPTIONS.items() if field in fields)


def _with_width(scene: Scene, factor: float) -> Scene:
    """Ribbons `factor` times as wide and as much more transparent (the same hair mass)."""
    strands = scene.strands
    return scene.replace(
        strands=strands.replace(width=strands.width * factor, alpha=np.minimum(strands.alpha / factor, 1.0))
    )


def _with_shadow_option(scene: Scene, key: str, value: int) -> Scene:
    """Through the registry: a shadow method without the option is a SceneError naming it."""
    options = {**dataclasses.asdict(scene.shadows), key: int(value)}
    return scene.replace(shadows=Shadows(scene.shadows.method, **options))


def _with_shadow_method(scene: Scene, method: str) -> Scene:
    """The registered shadow method `method`, keeping the scene's options that it takes
    (the map count and resolution where it has them) and its defaults for the rest."""
    fields = {f.name for f in dataclasses.fields(shadow_method_class(method))}
    options = {k: v for k, v in dataclasses.asdict(scene.shadows).items() if k in fields}
    return scene.replace(shadows=Shadows(method, **options))


def _option_setter(field: str) -> Callable:
    return lambda s, v: (_with_shadow_option(s, field, v), 1)


# Each knob: (scene, value) → (scene, supersampling factor). A `bins` value is a bin
# count, or the name of a registered ordering (e.g. "exact") to draw with instead.
_KNOB_SETTERS: dict[str, Callable] = {
    **{knob: _option_setter(field) for knob, field in SHADOW_OPTIONS.items()},
    "bins": lambda s, v: (
        s.replace(ordering=Ordering(v) if isinstance(v, str) else Ordering("bins", int(v))),
        1,
    ),
    "width": lambda s, v: (_with_width(s, float(v)), 1),
    "supersampling": lambda s, v: (s, int(v)),
    "shadows": lambda s, v: (_with_shadow_method(s, str(v)), 1),
}


def knob_scene(scene: Scene, knob: str, value) -> tuple[Scene, int]:
    """The scene with one knob set, and the supersampling factor to render it with."""
    if knob not in _KNOB_SETTERS:
        raise SweepError(f"unknown knob {knob!r}; knobs: {', '.join(KNOBS)}")
    return _KNOB_SETTERS[knob](scene, value)


def settings_scene(scene: Scene, settings: Mapping) -> tuple[Scene, int]:
    """The scene with every knob of `settings` (knob → value) set, and the supersampling
    factor: the shadow method first, so that its options are set on it."""
    s = 1
    for knob in sorted(settings, key=lambda k: k != "shadows"):
        scene, factor = knob_scene(scene, knob, settings[knob])
        s = max(s, factor)
    return scene, s


def reference_scene(scene: Scene, knobs: Mapping) -> tuple[Scene, int]:
    """Exact shadows (when the scene has shadows) at the scene's map resolution, exact
    ordering, the finest supersampling swept.

    The resolution stays the scene's: ribbons are w texels wide in the light's view
    (docs/model.md §7), so a finer map draws thinner hair and Ω does not converge as the
    resolution grows; the `map_resolution` knob shows how far it moves instead."""
    shadows = Shadows("exact", resolution=scene.shadows.resolution) if scene.shadows.casts else scene.shadows
    s = max(knobs.get("supersampling", (1,)))
    return scene.replace(shadows=shadows, ordering=Ordering("exact")), int(s)


def reference_config(scene: Scene, knobs: Mapping) -> dict:
    """`reference_scene(scene, knobs)` in words, for a sweep's or a search's config file."""
    reference, s = reference_scene(scene, knobs)
    shadows = reference.shadows
    return {
        "shadows": f"exact at {shadows.resolution}²" if shadows.casts else "none",
        "ordering": "exact",
        "supersampling": s,
    }
