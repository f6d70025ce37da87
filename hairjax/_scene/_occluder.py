"""The occluder (docs/model.md §9, §13): an opaque sphere or triangle mesh (a head) that
hides hair, receives its shadow and casts its own."""

from __future__ import annotations

import dataclasses
from typing import Literal

import numpy as np

from .._errors import SceneError
from .._values._light import RGBInput, Vec3Like, rgb, vec3
from .._values._strands import ArrayInput

__all__ = ["Occluder", "OCCLUDER_KINDS"]


OCCLUDER_KINDS = ("sphere", "mesh")


@dataclasses.dataclass(frozen=True)
class Occluder:
    """An opaque Lambertian occluder drawn before the hair; hair behind it is hidden, it
    receives the hair's shadow and casts its own (docs/model.md §9, §13).

    `kind="sphere"`: `center`, `radius`. `kind="mesh"`: a triangle mesh, from an OBJ file
    at `path` (read at construction) or given as `vertices` (`[V, 3]`) and `triangles`
    (`[F, 3]`, 0-based). Both are in the hair's world coordinates.
    """

    kind: Literal["sphere", "mesh"] = "sphere"
    # Stored as tuples of 3 floats, a float and (a mesh) read-only float64 and int32 arrays;
    # taken as any `Vec3Like`, number and array-likes, checked here (SceneError).
    center: Vec3Like = (0.0, 0.0, 0.0)
    radius: float | int = 1.0
    color: RGBInput = (0.5, 0.5, 0.5)
    path: str | None = None
    vertices: ArrayInput | None = dataclasses.field(default=None, compare=False, repr=False)
    triangles: ArrayInput | None = dataclasses.field(default=None, compare=False, repr=False)

    def __post_init__(self):
        if self.kind not in OCCLUDER_KINDS:
            raise SceneError(f"occluder.kind must be one of {OCCLUDER_KINDS}, got {self.kind!r}")
        object.__setattr__(self, "center", vec3("occluder.center", self.center))
        if not (np.isfinite(self.radius) and self.radius > 0):
            raise SceneError(f"occluder.radius must be positive, got {self.radius!r}")
        object.__setattr__(self, "radius", float(self.radius))
        object.__setattr__(self, "color", rgb("occluder.color", self.color))
        if self.kind == "sphere":
            if self.path is not None or self.vertices is not None or self.triangles is not None:
                raise SceneError("occluder.path, vertices and triangles are for kind 'mesh' only")
            return
        vertices, triangles = self.vertices, self.triangles
        if self.path is not None:
            if vertices is not None or triangles is not None:
                raise SceneError("occluder: give either path or vertices and triangles, not both")
            from .._io._obj import load_obj  # Lazy: only mesh occluders need the reader.

            try:
                vertices, triangles = load_obj(self.path)
            except ValueError as e:  # MeshFormatError names the file and line
                raise SceneError(f"occluder.path could not be loaded: {e}") from e
        elif vertices is None or triangles is None:
            raise SceneError("occluder kind 'mesh' needs path, or vertices and triangles")
        vertices = np.array(vertices, dtype=np.float64)
        triangles = np.array(triangles)
        if vertices.ndim != 2 or vertices.shape[1] != 3 or not np.all(np.isfinite(vertices)):
            raise SceneError(f"occluder.vertices must be finite [V, 3], got shape {vertices.shape}")
        if (
            triangles.ndim != 2
            or triangles.shape[1] != 3
            or len(triangles) == 0
            or not np.issubdtype(triangles.dtype, np.integer)
        ):
            raise SceneError(
                f"occluder.triangles must be integer [F, 3] with F ≥ 1, got "
                f"shape {triangles.shape} and dtype {triangles.dtype}"
            )
        if triangles.min() < 0 or triangles.max() >= len(vertices):
            raise SceneError(f"occluder.triangles index outside [0, {len(vertices)})")
        vertices.setflags(write=False)
        triangles = triangles.astype(np.int32)
        triangles.setflags(write=False)
        object.__setattr__(self, "vertices", vertices)
        object.__setattr__(self, "triangles", triangles)

    def __eq__(self, other):
        if not isinstance(other, Occluder):
            return NotImplemented
        same = (self.kind, self.center, self.radius, self.color, self.path) == (
            other.kind,
            other.center,
            other.radius,
            other.color,
            other.path,
        )
        if not same or self.kind == "sphere":
            return same
        return np.array_equal(self.vertices, other.vertices) and np.array_equal(
            self.triangles, other.triangles
        )
