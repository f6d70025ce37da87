"""The light (docs/model.md §1): directional or point, with a colour; and the small
value checks every part of a scene uses."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Literal

import numpy as np

from .._errors import SceneError

__all__ = ["Light", "vec3", "rgb", "Vec3Like", "RGBInput"]

# Three numbers as the scene's parts take them (a point, a direction, a colour): a tuple,
# list or array of ints or floats, which `vec3` and `rgb` check (SceneError) and store as
# a tuple of 3 floats. The int is spelled out: beartype, the tests' run-time checker, does
# not read `float` as PEP 484's "int too".
Vec3Like = Sequence[float | int] | np.ndarray
# A colour also as one number, for all three channels (`rgb` broadcasts it).
RGBInput = Vec3Like | float | int


def vec3(name: str, value, *, nonzero: bool = False) -> tuple[float, float, float]:
    arr = np.asarray(value, dtype=np.float64)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise SceneError(f"{name} must be 3 finite numbers, got {value!r}")
    if nonzero and not np.linalg.norm(arr) > 0:
        raise SceneError(f"{name} must not have length 0")
    return float(arr[0]), float(arr[1]), float(arr[2])


def rgb(name: str, value) -> tuple[float, float, float]:
    arr = np.broadcast_to(np.asarray(value, dtype=np.float64), (3,))
    if not np.all(np.isfinite(arr)) or np.any(arr < 0):
        raise SceneError(f"{name} must be a non-negative number or 3 of them, got {value!r}")
    return float(arr[0]), float(arr[1]), float(arr[2])


@dataclasses.dataclass(frozen=True)
class Light:
    """A directional light (`direction`: the way light travels) or a point light (`position`)."""

    kind: Literal["directional", "point"] = "directional"
    # Stored as tuples of 3 floats (`vec3`, `rgb`); taken as any `Vec3Like`.
    direction: Vec3Like | None = (-1.0, -1.0, -1.0)
    position: Vec3Like | None = None
    color: RGBInput = (1.0, 1.0, 1.0)

    def __post_init__(self):
        if self.kind == "directional":
            if self.direction is None:
                raise SceneError("light.direction is required for a directional light")
            object.__setattr__(self, "direction", vec3("light.direction", self.direction, nonzero=True))
            object.__setattr__(self, "position", None)
        elif self.kind == "point":
            if self.position is None:
                raise SceneError("light.position is required for a point light")
            object.__setattr__(self, "position", vec3("light.position", self.position))
            object.__setattr__(self, "direction", None)
        else:
            raise SceneError(f"light.kind must be 'directional' or 'point', got {self.kind!r}")
        object.__setattr__(self, "color", rgb("light.color", self.color))
