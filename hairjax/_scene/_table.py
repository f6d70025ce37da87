"""One table of a scene file being read, and the value checks every reader shares.

`Table`'s getters return None for an absent key (so the consumer's default applies) and
otherwise a checked Python value; every failure is a `SceneError` naming `table.key`,
what is allowed and what was found. Types are checked here, before any dataclass sees a
value, because NumPy would happily turn `true` into 1.0 or `"3"` into 3.0. Shading
models, shadow methods and orderings read their own keys with it (`from_table`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

from .._errors import SceneError

__all__ = ["Table", "build", "given", "is_number", "describe"]


class Table:
    """One TOML table being read.

    Each getter returns `None` for an absent key (so the consumer's default applies) and
    otherwise a checked Python value; every failure is a `SceneError` naming `table.key`.
    """

    def __init__(self, name: str, data: Mapping[str, Any], where: str, allowed: tuple[str, ...]):
        self.name = name
        self.data = data
        self.where = where
        for key in data:
            if key not in allowed:
                raise SceneError(
                    f"{where}: unknown key {name}.{key}; allowed keys in [{name}]: {', '.join(allowed)}"
                )

    @staticmethod
    def given(**kwargs) -> dict[str, Any]:
        """The keyword arguments whose value is not None (keys present in the table)."""
        return given(**kwargs)

    def __contains__(self, key: str) -> bool:
        return key in self.data

    def error(self, key: str, requirement: str, value: Any) -> SceneError:
        return SceneError(f"{self.where}: {self.name}.{key} must be {requirement}, got {describe(value)}")

    def number(
        self,
        key: str,
        *,
        lo: float | int | None = None,
        hi: float | int | None = None,
        lo_open: bool = False,
        hi_open: bool = False,
    ) -> float | None:
        """A finite number (TOML integer or float, not boolean), optionally in a range."""
        if key not in self.data:
            return None
        value = self.data[key]
        if not is_number(value) or not math.isfinite(value):
            raise self.error(key, "a finite number", value)
        requirement = range_text(lo, hi, lo_open, hi_open)
        if not in_range(value, lo, hi, lo_open, hi_open):
            raise self.error(key, requirement, value)
        return float(value)

    def integer(self, key: str, *, lo: int | None = None) -> int | None:
        """A TOML integer (not a float, not a boolean), optionally >= `lo`."""
        if key not in self.data:
            return None
        value = self.data[key]
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(key, "an integer", value)
        if lo is not None and value < lo:
            raise self.error(key, f"an integer >= {lo}", value)
        return value

    def choice(self, key: str, choices: tuple[str, ...]) -> str | None:
        """One of the strings in `choices`."""
        if key not in self.data:
            return None
        value = self.data[key]
        if not isinstance(value, str) or value not in choices:
            raise self.error(key, f"one of {', '.join(repr(c) for c in choices)}", value)
        return value

    def string(self, key: str) -> str | None:
        """A non-empty string."""
        if key not in self.data:
            return None
        value = self.data[key]
        if not isinstance(value, str) or not value:
            raise self.error(key, "a non-empty string", value)
        return value

    def vec3(self, key: str) -> tuple[float, float, float] | None:
        """An array of 3 finite numbers."""
        if key not in self.data:
            return None
        value = self.data[key]
        if not (
            isinstance(value, list)
            and len(value) == 3
            and all(is_number(x) and math.isfinite(x) for x in value)
        ):
            raise self.error(key, "an array of 3 finite numbers", value)
        x, y, z = (float(v) for v in value)
        return x, y, z

    def rgb(self, key: str, *, scalar: bool = False) -> Any:
        """A colour: an array of 3 numbers >= 0 (or, with `scalar`, also one number >= 0,
        which the consumer broadcasts to RGB)."""
        if key not in self.data:
            return None
        value = self.data[key]
        allowed = (
            "a number >= 0 or an array of 3 numbers >= 0" if scalar else "an array of 3 numbers >= 0 (RGB)"
        )
        if scalar and is_number(value):
            items = [value]
        elif isinstance(value, list) and len(value) == 3:
            items = value
        else:
            raise self.error(key, allowed, value)
        if not all(is_number(x) and math.isfinite(x) and x >= 0 for x in items):
            raise self.error(key, allowed, value)
        if isinstance(value, list):
            return tuple(float(x) for x in value)
        return float(value)

    def texture(self, key: str, *, rgb: bool) -> list | None:
        """A 1-D texture: a non-empty array of numbers, or (with `rgb`) of [r, g, b]
        arrays (types here; value ranges are the consumer's)."""
        value = self.data.get(key)
        if value is None:
            return None
        rows = value if isinstance(value, list) else []
        items = [x for row in rows for x in (row if isinstance(row, list) else [None])] if rgb else rows
        if (
            not rows
            or not all(is_number(x) for x in items)
            or (rgb and not all(len(row) == 3 for row in rows))
        ):
            raise self.error(
                key, "a non-empty array of [r, g, b] arrays" if rgb else "a non-empty array of numbers", value
            )
        return value

    def options(self, cls, skip: tuple[str, ...] = ()) -> dict[str, Any]:
        """The present keys among the dataclass fields of `cls` (but `skip`), each read
        by the type of the field's default (int: integer, float: number, str: string)."""
        import dataclasses

        out = {}
        for f in dataclasses.fields(cls):
            if f.name in skip or f.name not in self.data:
                continue
            readers: dict[type, Callable[[str], Any]] = {
                bool: self.boolean,
                int: self.integer,
                float: self.number,
                str: self.string,
            }
            reader = readers.get(type(f.default), self.number)
            out[f.name] = reader(f.name)
        return out

    def boolean(self, key: str) -> bool | None:
        if key not in self.data:
            return None
        value = self.data[key]
        if not isinstance(value, bool):
            raise self.error(key, "true or false", value)
        return value

    def only_keys_of(self, kind: str, choice: str, keys: tuple[str, ...]) -> None:
        """`SceneError` for a key of this table that the chosen `kind` (e.g. model =
        'kajiya-kay') does not read: it would be silently ignored otherwise."""
        for key in self.data:
            if key != kind and key not in keys:
                raise SceneError(f"{self.where}: {self.name}.{key} is not a key of {kind} = {choice!r}")


def build(where: str, factory, **kwargs):
    """Construct a scene dataclass; its own SceneError gains the file path."""
    try:
        return factory(**kwargs)
    except SceneError as e:
        if str(e).startswith(f"{where}: "):  # a table's own check: it named the file already
            raise
        raise SceneError(f"{where}: {e}") from e


def given(**kwargs) -> dict[str, Any]:
    """The keyword arguments whose value is not None (i.e. keys present in the file)."""
    return {k: v for k, v in kwargs.items() if v is not None}


def is_number(value: Any) -> bool:
    # bool is an int subclass in Python, but `true` is not a number in a scene file.
    return isinstance(value, int | float) and not isinstance(value, bool)


def in_range(value: float | int, lo, hi, lo_open: bool, hi_open: bool) -> bool:
    if lo is not None and (value <= lo if lo_open else value < lo):
        return False
    if hi is not None and (value >= hi if hi_open else value > hi):
        return False
    return True


def range_text(lo, hi, lo_open: bool, hi_open: bool) -> str:
    """'> 0', '>= 0', 'in (0, 1]', ... for error messages."""
    if lo is not None and hi is not None:
        return f"in {'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'}"
    if lo is not None:
        return f"{'>' if lo_open else '>='} {lo:g}"
    if hi is not None:
        return f"{'<' if hi_open else '<='} {hi:g}"
    return "a finite number"


def toml_type(value: Any) -> str:
    if isinstance(value, bool):
        return "boolean"
    if isinstance(value, int):
        return "integer"
    if isinstance(value, float):
        return "float"
    if isinstance(value, str):
        return "string"
    if isinstance(value, list):
        return "array"
    if isinstance(value, Mapping):
        return "table"
    return "date/time"


def show(value: Any) -> str:
    """A value roughly as TOML writes it (true, not True)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, list):
        return "[" + ", ".join(show(x) for x in value) + "]"
    if isinstance(value, Mapping):
        return "{" + ", ".join(f"{k} = {show(v)}" for k, v in value.items()) + "}"
    return repr(value)


def describe(value: Any) -> str:
    """A value for an error message. Numbers are shown bare ('got -1'); other types also
    name their TOML type, since '"3"' and '3' look alike to a reader skimming the message."""
    if is_number(value):
        return show(value)
    return f"{show(value)} ({toml_type(value)})"
