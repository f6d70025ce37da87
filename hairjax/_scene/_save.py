"""A `Scene` back into a scene file: `save_scene(scene, path)` writes the TOML that
`load_scene` reads to the same scene and the same image (docs/scenes.md, "Saving a scene").

Every table is written from the scene's values (the camera as placed, framing done; the
shading model's parameters; every field of the shadow method and ordering), except what a
`Scene` holds no values for: `[hair]`'s source and generator keys and `[animation]`, which
come from `Scene.file_tables` (what `load_scene` read). Numbers are written as the
shortest decimal that reads back to the same float, so nothing is rounded.

TOML writing is `tomli_w`'s, the writer that pairs with the standard library's `tomllib`
reader (same data model, floats written round-trip exact), rather than hand-formatting.
"""

from __future__ import annotations

import dataclasses
import os
import re
from pathlib import Path
from typing import Any

import numpy as np

from .._errors import SceneError
from ._scene import Scene

__all__ = ["save_scene", "scene_data"]


# An array of numbers as tomli_w writes it, one number a line; `_compact` puts it on one.
_NUMBER_ARRAY = re.compile(r"\[\n((?:[ ]+[-+]?(?:[0-9][0-9_.eE+-]*|inf|nan),\n)+)[ ]*\]")


def _compact(text: str) -> str:
    """`text` with each array of numbers on one line: `kd = [0.55, 0.35, 0.2]`."""
    return _NUMBER_ARRAY.sub(lambda m: "[" + ", ".join(x.strip(" ,") for x in m[1].splitlines()) + "]", text)


def _toml(value: Any) -> Any:
    """`value` as TOML data: tuples and arrays as lists, NumPy scalars as Python numbers."""
    if isinstance(value, dict):
        return {k: _toml(v) for k, v in value.items()}
    if isinstance(value, (tuple, list)):
        return [_toml(v) for v in value]
    if isinstance(value, np.ndarray):
        return _toml(value.tolist())
    if isinstance(value, np.generic):
        return value.item()
    return value


def _fields(obj, skip: tuple[str, ...] = ()) -> dict[str, Any]:
    """The dataclass fields of `obj` that hold a value (None: the default applies)."""
    return {
        f.name: getattr(obj, f.name)
        for f in dataclasses.fields(obj)
        if f.name not in skip and getattr(obj, f.name) is not None
    }


def _camera(scene: Scene) -> dict[str, Any]:
    camera = scene.camera
    if any(float(x) != 0.0 for x in camera.offset):
        raise SceneError(
            f"camera.offset {tuple(camera.offset)} has no scene-file key: a supersampling "
            "sub-image cannot be saved; save the scene it came from"
        )
    return _fields(camera, skip=("offset",))


def _light(scene: Scene) -> dict[str, Any]:
    return _fields(scene.light)


def _occluder(scene: Scene) -> dict[str, Any]:
    occluder = scene.occluder
    assert occluder is not None
    keys = ("kind", "center", "radius", "color") if occluder.kind == "sphere" else ("kind", "path", "color")
    return {k: getattr(occluder, k) for k in keys}


def _hair(scene: Scene) -> dict[str, Any]:
    tables = scene.file_tables or {}
    if "hair" not in tables:
        raise SceneError(
            "the scene's strands came from no scene file's [hair] table (built in Python, or "
            "replaced with scene.replace(strands=…)): a scene file cannot describe them; "
            "save the strands as a hair file and load a scene that names it"
        )
    hair = dict(tables["hair"])
    patches = scene.patches
    if patches is not None:
        hair.update(
            geometry="patches",
            patch_width=patches.width,
            opaque_core=patches.opaque_core,
            patch_strands=patches.strands,
            patch_strand_alpha=patches.strand_alpha,
            patch_strand_tips=patches.tips,
        )
    return hair


def scene_data(scene: Scene) -> dict[str, Any]:
    """The scene file's tables for `scene`, as TOML data (`save_scene` writes them).

    **Raises:** `SceneError` for a scene a file cannot describe: strands not from a
    `[hair]` table (`Scene.file_tables`), or a camera with a sub-pixel `offset`.
    """
    data: dict[str, Any] = {"name": scene.name, "hair": _hair(scene)}
    data["camera"] = _camera(scene)
    data["light"] = _light(scene)
    data["shading"] = scene.shading.table()
    data["shadows"] = {"method": scene.shadows.method, **_fields(scene.shadows)}
    data["ordering"] = {"method": scene.ordering.method, **_fields(scene.ordering)}
    if scene.occluder is not None:
        data["occluder"] = _occluder(scene)
    data["background"] = {"color": scene.background}
    if scene.streaks is not None:
        data["streaks"] = _fields(scene.streaks)
    if "animation" in (scene.file_tables or {}):
        data["animation"] = dict((scene.file_tables or {})["animation"])
    if scene.reference is not None:
        data["reference"] = _fields(scene.reference)
    return _toml(data)


def save_scene(scene: Scene, path: str | os.PathLike) -> Path:
    """Write `scene` as a TOML scene file at `path` (atomically): `load_scene(path)` reads
    it back to the same scene, and so renders the same image.

    A hair file the scene was read from is named by its absolute path; a procedural
    source keeps its generator's keys, so the strands are generated again, the same. A
    framed camera (`frame = "auto"`) is written as the eye, target and up it placed.

    **Raises:** `SceneError` for a path that does not end in `.toml`, or a scene a file
    cannot describe (`scene_data`); `OSError` for a file that cannot be written.
    """
    import tomli_w

    from .._io._files import write_text

    path = Path(path)
    if path.suffix.lower() != ".toml":
        raise SceneError(f"{path}: a scene file ends in .toml")
    return write_text(path, _compact(tomli_w.dumps(scene_data(scene))))
