"""A scene file's data with the command line's changes (`--set`, `--unset`): keys set or
removed, a switched model or method's stale keys dropped, and errors blamed on the option
that set the key they name (docs/scenes.md, "Rules")."""

from __future__ import annotations

import re
import warnings
from collections.abc import Mapping
from typing import Any

from .._errors import SceneError
from ._keys import CHOICES, TOP_LEVEL_KEYS, choice_keys, scene_tables

__all__ = ["with_overrides", "blamed_on", "UNSET"]


class _Unset:
    """The value of an override that removes its key (`hairjax … --unset table.key`)."""

    def __repr__(self) -> str:
        return "UNSET"


UNSET: Any = _Unset()


def with_overrides(data: Mapping[str, Any], overrides: Mapping[str, Any], where: str) -> dict[str, Any]:
    """`data` (parsed TOML) with each `"table.key": value` of `overrides` set, in a copy; a
    value `UNSET` removes the key. Setting (or removing) `shading.model`, `shadows.method`
    or `ordering.method` also removes the table's other keys from `data` that the new
    choice does not read, with a warning naming them (`_switched`).

    **Raises:** `SceneError` naming the key, and the allowed tables or keys, for a table
    or key that no scene file may hold (a typo); values are checked later, with the file's.
    """
    out: dict[str, Any] = {k: dict(v) if isinstance(v, Mapping) else v for k, v in data.items()}
    tables = scene_tables()
    for dotted, value in overrides.items():
        if dotted in TOP_LEVEL_KEYS:
            if value is UNSET:
                out.pop(dotted, None)
            else:
                out[dotted] = value
            continue
        table, _, key = dotted.partition(".")
        if table not in tables:
            raise SceneError(f"{where}: no table [{table}] for {dotted!r}; tables: {', '.join(tables)}")
        if key not in tables[table]:
            raise SceneError(
                f"{where}: [{table}] has no key {key!r} ({dotted!r}); keys: {', '.join(tables[table])}"
            )
        entry = out.setdefault(table, {})
        if not isinstance(entry, dict):  # the file holds `table = value`, not a table: refused later
            raise SceneError(f"{where}: {table} is not a table, so {dotted!r} cannot be set")
        if value is UNSET:
            entry.pop(key, None)
        else:
            entry[key] = value
    _switched(out, overrides, where)
    return out


def _switched(out: dict[str, Any], overrides: Mapping[str, Any], where: str) -> None:
    """Where `overrides` set (or removed) a table's choice, drop the keys of that table
    that came from the file and that the new choice does not read (the default scene's
    `shadows.maps` when switching to "exact"), and warn once naming them."""
    for table, key, default in CHOICES:
        entry = out.get(table)
        if f"{table}.{key}" not in overrides or not isinstance(entry, dict):
            continue
        choice = entry.get(key, default)
        reads = choice_keys(table, choice)
        if reads is None:
            continue
        dropped = [k for k in entry if k != key and k not in reads and f"{table}.{k}" not in overrides]
        for k in dropped:
            del entry[k]
        if dropped:
            keys = ", ".join(f"{table}.{k}" for k in dropped)
            warnings.warn(f"{where}: {table}.{key} = {choice!r} does not read {keys}: dropped", stacklevel=3)


_DOTTED = re.compile(r"\b([a-z_]+\.[a-z_]+)\b")


def blamed_on(err: SceneError, where: str, origins: Mapping[str, str]) -> SceneError:
    """`err` (a message `where: …`) blamed on the command-line option that set the key it
    names first (`origins`: `"table.key"` → e.g. `"--set shading.kd=-1"`), or `err`
    itself when that key came from the file."""
    text = str(err)
    if not text.startswith(f"{where}: "):
        return err
    rest = text[len(where) + 2 :]
    first = _DOTTED.search(rest)
    if first is None or first.group(1) not in origins:
        return err
    try:
        return type(err)(f"{origins[first.group(1)]}: {rest}")  # SceneTooLarge stays one
    except TypeError:  # a subclass whose constructor takes other arguments
        return SceneError(f"{origins[first.group(1)]}: {rest}")
