"""The spaces the settings search walks (docs/results.md §1 and §7), and a setting's key.

`KnobSpace`, the joint search's: every combination of the knobs, and the single-knob steps
between combinations. `OneKnobSpace`, the one-knob sweep's: each setting changes one knob
from the scene's settings, the others keep them. The search (`_search.py`) takes either.

A setting is a dict knob → value. The knob `shadows` names the shadow method; a knob that
sets a field of the method (`SHADOW_OPTIONS`: `maps`, `map_resolution`, `layers`) is in a
setting only when that method has the field, so exact shadows have no `maps`, no shadows
have none of them, and a method registered with a `layers` field has `layers`. The other
knobs (`bins`, `width`, `supersampling`) are in every setting. Each knob's values are
listed cheapest first (as `KNOBS` lists them).
"""

from __future__ import annotations

import dataclasses
import itertools
import json
import math
from collections.abc import Iterator, Mapping, Sequence

from .._scene._scene import Scene
from ._knobs import SHADOW_KNOBS, SHADOW_OPTIONS, method_options

__all__ = [
    "METHOD",
    "KnobSpace",
    "OneKnobSpace",
    "knob_space",
    "one_knob_space",
    "setting_key",
    "setting_label",
]

METHOD = "shadows"  # the knob naming the shadow method


@dataclasses.dataclass(frozen=True)
class KnobSpace:
    """`knobs`: name → values, cheapest first; `options`: each shadow method of the space
    → the option knobs it takes; `method`: the method of every setting when `shadows` is
    not a knob (the scene's)."""

    knobs: Mapping[str, tuple]
    options: Mapping[str, tuple[str, ...]]
    method: str

    @property
    def methods(self) -> tuple[str, ...]:
        return tuple(self.knobs[METHOD]) if METHOD in self.knobs else (self.method,)

    def active(self, method: str) -> tuple[str, ...]:
        """The knobs of a setting with shadow method `method`, in the space's order."""
        options = {k for m in self.options.values() for k in m}
        return tuple(k for k in self.knobs if k not in options or k in self.options[method])

    def method_of(self, setting: Mapping) -> str:
        return setting.get(METHOD, self.method)

    def start(self) -> dict:
        """The cheapest setting: every knob at its first value."""
        return self._with_method({}, self.methods[0])

    def _with_method(self, setting: Mapping, method: str) -> dict:
        """`setting` with shadow method `method`: the knobs it shares with the old method
        keep their values, the method's other options start at their first values."""
        out = {}
        for k in self.active(method):
            out[k] = method if k == METHOD else setting.get(k, self.knobs[k][0])
        return out

    def up(self, setting: Mapping, knob: str) -> dict | None:
        """`setting` with `knob` (not `shadows`) at its next value (more maps, a finer
        raster, more bins, wider ribbons, more samples); None at its last."""
        values = self.knobs[knob]
        i = values.index(setting[knob])
        return {**setting, knob: values[i + 1]} if i + 1 < len(values) else None

    def switches(self, setting: Mapping) -> list[dict]:
        """`setting` with each other shadow method (none is above another)."""
        if METHOD not in setting:
            return []
        return [self._with_method(setting, m) for m in self.methods if m != setting[METHOD]]

    def ordered(self, setting: Mapping) -> tuple[str, ...]:
        """The knobs of `setting` that `up` steps: all but `shadows`."""
        return tuple(k for k in self.active(self.method_of(setting)) if k != METHOD)

    def steps(self, setting: Mapping) -> list[dict]:
        """The settings one step from `setting`: each knob one value up, each other method."""
        ups = [self.up(setting, k) for k in self.ordered(setting)]
        return [s for s in ups if s is not None] + self.switches(setting)

    def grid(self) -> Iterator[dict]:
        """Every setting of the space (for checking the search on a small one)."""
        for method in self.methods:
            names = self.active(method)
            values = [(method,) if k == METHOD else self.knobs[k] for k in names]
            for combination in itertools.product(*values):
                yield dict(zip(names, combination))

    def size(self) -> int:
        """The number of settings in `grid()`."""
        return sum(
            math.prod(1 if k == METHOD else len(self.knobs[k]) for k in self.active(m)) for m in self.methods
        )

    def label(self, setting: Mapping) -> str:
        """A setting in a progress line: `bins=16 maps=4`."""
        return setting_label(setting)

    def to_json(self) -> dict:
        return {
            "knobs": {k: list(v) for k, v in self.knobs.items()},
            "options": {m: list(v) for m, v in self.options.items()},
            "method": self.method,
        }

    @classmethod
    def from_json(cls, data: Mapping) -> KnobSpace:
        return cls(
            {k: tuple(v) for k, v in data["knobs"].items()},
            {m: tuple(v) for m, v in data["options"].items()},
            data["method"],
        )


def knob_space(scene: Scene, knobs: Mapping[str, Sequence]) -> KnobSpace:
    """The space of `knobs` (name → values) for `scene`: without shadows in the scene, no
    shadow knobs (its reference has none); without the `shadows` knob, the scene's method
    throughout; an option knob that no method of the space takes is dropped."""
    kept = {k: tuple(v) for k, v in knobs.items() if scene.shadows.casts or k not in SHADOW_KNOBS}
    method = scene.shadows.method
    methods = kept.get(METHOD, (method,))
    options = {m: tuple(k for k in method_options(m) if k in kept) for m in methods}
    taken = {k for m in options.values() for k in m}
    searched = {k: v for k, v in kept.items() if k not in SHADOW_OPTIONS or k in taken}
    return KnobSpace(searched, options, method)


@dataclasses.dataclass(frozen=True)
class OneKnobSpace:
    """The one-knob sweep's space: `knobs`, name → values in the order swept; a setting is
    `{knob: value}`, one knob changed from the scene's settings (`settings_scene` sets only
    the knobs a setting names)."""

    knobs: Mapping[str, tuple]

    def grid(self) -> Iterator[dict]:
        """Every setting: each knob's values in turn, the knobs in the space's order."""
        for knob, values in self.knobs.items():
            for value in values:
                yield {knob: value}

    def size(self) -> int:
        return sum(len(values) for values in self.knobs.values())

    def label(self, setting: Mapping) -> str:
        """A setting in a progress line or a report: `bins = 16`."""
        ((knob, value),) = setting.items()
        return f"{knob} = {value}"

    def to_json(self) -> dict:
        return {k: list(v) for k, v in self.knobs.items()}

    @classmethod
    def from_json(cls, data: Mapping) -> OneKnobSpace:
        return cls({k: tuple(v) for k, v in data.items()})


def one_knob_space(scene: Scene, knobs: Mapping[str, Sequence]) -> OneKnobSpace:
    """The knobs of `knobs` that turn something in `scene`: a scene without shadows has no
    shadow knobs, and a knob setting a field the scene's shadow method lacks (`maps` of
    exact shadows) is dropped."""
    takes = method_options(scene.shadows.method)
    return OneKnobSpace(
        {
            k: tuple(v)
            for k, v in knobs.items()
            if (scene.shadows.casts or k not in SHADOW_KNOBS) and (k not in SHADOW_OPTIONS or k in takes)
        }
    )


def setting_key(setting: Mapping) -> str:
    """A setting's key: the same for the same knob values, in any order."""
    return json.dumps(dict(setting), sort_keys=True)


def setting_label(setting: Mapping) -> str:
    return " ".join(f"{k}={v}" for k, v in setting.items())
