"""Wavefront OBJ triangle meshes (``.obj``), for the occluder (docs/model.md §13).

Read: ``v x y z [w]`` (w ignored) and ``f`` with one of the vertex forms ``v``, ``v/vt``,
``v//vn``, ``v/vt/vn`` (only the position index is used; indices are 1-based, negative
ones count back from the last vertex read so far); a polygon with n ≥ 3 corners is fanned
into the triangles (0, k, k + 1). Every other statement (``vt``, ``vn``, ``o``, ``g``,
``s``, ``usemtl``, ``mtllib``, comments) is ignored. Anything malformed raises
`MeshFormatError` naming the file and the line, a vertex coordinate that is not finite or
lies beyond ±`COORDINATE_BOUND` (1e18, hairjax/_constants.py) included.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .._constants import COORDINATE_BOUND
from .._errors import MeshFormatError

__all__ = ["parse_obj", "load_obj"]


def load_obj(path) -> tuple[np.ndarray, np.ndarray]:
    """Read an OBJ file: (vertices `float64[V, 3]`, triangles `int32[F, 3]`, 0-based).

    **Raises:** `MeshFormatError` naming the file (and the line) when it cannot be read or
    is malformed."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as error:
        raise MeshFormatError(path, None, f"cannot read the file: {error.strerror or error}") from error
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as error:
        raise MeshFormatError(path, None, f"not UTF-8 text: {error}") from error
    return parse_obj(text, path)


def parse_obj(text: str, path) -> tuple[np.ndarray, np.ndarray]:
    """Parse OBJ text; see `load_obj`."""
    vertices: list[tuple[float, float, float]] = []
    triangles: list[tuple[int, int, int]] = []
    for number, raw in enumerate(text.splitlines(), start=1):
        words = raw.split("#", 1)[0].split()
        if not words:
            continue
        if words[0] == "v":
            if len(words) not in (4, 5):
                raise MeshFormatError(
                    path,
                    number,
                    f"'v' needs 3 coordinates (and an optional w), got {len(words) - 1}: {raw.strip()!r}",
                )
            try:
                xyz = (float(words[1]), float(words[2]), float(words[3]))
            except ValueError:
                raise MeshFormatError(
                    path, number, f"'v' coordinates must be numbers: {raw.strip()!r}"
                ) from None
            if not all(math.isfinite(c) for c in xyz):
                raise MeshFormatError(path, number, f"'v' coordinates must be finite: {raw.strip()!r}")
            if not all(abs(c) <= COORDINATE_BOUND for c in xyz):
                raise MeshFormatError(
                    path,
                    number,
                    f"'v' coordinates must lie within ±{COORDINATE_BOUND:g} (the bound that keeps the "
                    f"float32 projection finite, docs/scenes.md): {raw.strip()!r}",
                )
            vertices.append(xyz)
        elif words[0] == "f":
            if len(words) < 4:
                raise MeshFormatError(
                    path, number, f"'f' needs at least 3 vertices, got {len(words) - 1}: {raw.strip()!r}"
                )
            corners = [_vertex_index(w, len(vertices), path, number) for w in words[1:]]
            triangles.extend((corners[0], corners[k], corners[k + 1]) for k in range(1, len(corners) - 1))
    if not vertices:
        raise MeshFormatError(path, None, "no vertices ('v' lines)")
    if not triangles:
        raise MeshFormatError(path, None, "no faces ('f' lines)")
    return np.asarray(vertices, np.float64), np.asarray(triangles, np.int32)


def _vertex_index(word: str, count: int, path, line: int) -> int:
    """The 0-based position index of one face corner `v`, `v/vt`, `v//vn` or `v/vt/vn`."""
    parts = word.split("/")
    if len(parts) > 3 or not parts[0] or (len(parts) == 3 and not parts[2]):
        raise MeshFormatError(path, line, f"face vertex {word!r} is not v, v/vt, v//vn or v/vt/vn")
    for part in parts[1:]:
        if part and not part.lstrip("-").isdigit():
            raise MeshFormatError(path, line, f"face vertex {word!r}: {part!r} is not an index")
    try:
        index = int(parts[0])
    except ValueError:
        raise MeshFormatError(path, line, f"face vertex {word!r}: {parts[0]!r} is not an index") from None
    if index == 0:
        raise MeshFormatError(path, line, f"face vertex {word!r}: indices start at 1 (0 is not allowed)")
    resolved = index - 1 if index > 0 else count + index  # −1 is the last vertex read so far
    if not 0 <= resolved < count:
        raise MeshFormatError(
            path,
            line,
            f"face vertex {word!r} refers to vertex {index}, but {count} vertices are defined so far",
        )
    return resolved
