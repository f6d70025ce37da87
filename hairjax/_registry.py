"""The registries of the extension points (docs/architecture.md): shading models, shadow
methods and orderings each register their classes under the name a scene file gives them
(`[shading] model`, `[shadows] method`, `[ordering] method`)."""

from __future__ import annotations

import dataclasses
from typing import Any, Generic, TypeVar

from ._errors import SceneError

__all__ = ["Registry"]

T = TypeVar("T")


class Registry(Generic[T]):
    """Classes by name. `table`/`key`: where a scene file names them (messages read
    `shadows.method must be one of …`); `attribute`: the class attribute holding the name."""

    def __init__(self, table: str, key: str, attribute: str):
        self.table, self.key, self.attribute = table, key, attribute
        self.classes: dict[str, type[T]] = {}

    def register(self, cls: type[T]) -> type[T]:
        """Class decorator: make `cls` available under its name (a name registered twice
        is the later class's)."""
        self.classes[getattr(cls, self.attribute)] = cls
        return cls

    def names(self) -> tuple[str, ...]:
        return tuple(self.classes)

    def get(self, name: str) -> type[T]:
        """The class called `name`; `SceneError` listing the names if none."""
        try:
            return self.classes[name]
        except (KeyError, TypeError):  # TypeError: not a string (an unhashable value)
            raise SceneError(f"{self.table}.{self.key} must be one of {self.names()}, got {name!r}") from None

    def make(self, name: str, *args: Any, **options: Any) -> T:
        """An instance of the class called `name` from its dataclass fields, in order or
        by name; `SceneError` for an option the class does not take."""
        cls = self.get(name)
        if args:
            return cls(*args, **options)
        keys = tuple(f.name for f in dataclasses.fields(cls))  # type: ignore[arg-type]
        for key in options:
            if key not in keys:
                takes = ", ".join(keys) if keys else "no options"
                raise SceneError(
                    f"{self.table}.{key} is not a key of {self.key} = {name!r} (it takes {takes})"
                )
        return cls(**options)
