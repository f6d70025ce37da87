"""The light (docs/model.md §1): directional or point, with a colour; and the small
value checks every part of a scene uses."""

from __future__ import annotations

import dataclasses
from typing import Literal

import numpy as np

from .._errors import SceneError

__all__ = ["Light", "vec3", "rgb"]


def vec3(name: str, value, *, nonzero: bool = False) -> tuple[float, float, float]:
    arr = np.asarray(value, dtype=np.float64)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise SceneError(f"{name} must be 3 finite numbers, got {value!r}")
    if nonzero and not np.linalg.norm(arr) > 0:
        raise SceneError(f"{name} must not have length 0")
    return tuple(float(x) for x in arr)


def rgb(name: str, value) -> tuple[float, float, float]:
    arr = np.broadcast_to(np.asarray(value, dtype=np.float64), (3,))
    if not np.all(np.isfinite(arr)) or np.any(arr < 0):
        raise SceneError(f"{name} must be a non-negative number or 3 of them, got {value!r}")
    return tuple(float(x) for x in arr)


@dataclasses.dataclass(frozen=True)
class Light:
    """A directional light (`direction`: the way light travels) or a point light (`position`)."""

    kind: Literal["directional", "point"] = "directional"
    direction: tuple[float, float, float] | None = (-1.0, -1.0, -1.0)
    position: tuple[float, float, float] | None = None
    color: tuple[float, float, float] = (1.0, 1.0, 1.0)

    def __post_init__(self):
        if self.kind == "directional":
            if self.direction is None:
                raise SceneError("light.direction is required for a directional light")
            object.__setattr__(self, "direction",
                               vec3("light.direction", self.direction, nonzero=True))
            object.__setattr__(self, "position", None)
        elif self.kind == "point":
            if self.position is None:
                raise SceneError("light.position is required for a point light")
            object.__setattr__(self, "position", vec3("light.position", self.position))
            object.__setattr__(self, "direction", None)
        else:
            raise SceneError(f"light.kind must be 'directional' or 'point', got {self.kind!r}")
        object.__setattr__(self, "color", rgb("light.color", self.color))
