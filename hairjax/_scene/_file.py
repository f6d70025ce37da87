"""Scene files: TOML text -> `Scene`.

A scene file has one table per part of the scene (`[hair]`, `[camera]`, `[light]`,
`[shading]`, `[shadows]`, `[ordering]`, `[occluder]`, `[background]`, `[streaks]`,
`[animation]`, `[reference]`) and an optional
top-level `name`; docs/scenes.md documents every key. Every key but `hair.source` is
optional, and an absent key takes the default of the dataclass (or generator) it feeds,
so defaults live in one place.

Errors: everything wrong with a file raises a single `SceneError` whose message starts
with the file path and names the key as `table.key`, what is allowed, and what was found.
Types are checked here (`_scene_table.Table`), before any dataclass sees a value, because
NumPy would happily turn `true` into 1.0 or `"3"` into 3.0; value ranges are the checks of
the objects the values build (the scene's dataclasses, the shading parameters), whose
errors are re-raised with the file path. [shading], [shadows] and [ordering] name a
registered model, shadow method or ordering, which reads its own keys.
"""

from __future__ import annotations

import dataclasses
import os
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from .._errors import SceneError
from .._geometry._ordering import ordering_class, ordering_names
from .._geometry._shadows import shadow_method_class, shadow_method_names
from .._shading import Streaks, shading_model_class, shading_model_names
from .._values._camera import Camera
from .._values._light import Light
from ._framing import WIDTH_FRACTION, bounding_sphere, frame_camera, key_light
from ._hair_table import PROCEDURAL_SOURCES, read_hair, read_patches
from ._keys import PATCH_KEYS, TOP_LEVEL_KEYS, field_names, scene_tables
from ._occluder import OCCLUDER_KINDS, Occluder
from ._overrides import UNSET, blamed_on, with_overrides
from ._reference import ReferenceSettings, read_reference
from ._scene import Scene
from ._table import Table, build, describe, given

__all__ = [
    "load_scene",
    "scene_from_dict",
    "default_scene_path",
    "scene_tables",
    "with_overrides",
    "scene_for_hair",
    "UNSET",
    "blamed_on",
]


LIGHT_KINDS = ("directional", "point")
CAMERA_FRAMES = ("auto",)
MESH_FILE_SUFFIXES = (".obj",)


def default_scene_path() -> Path:
    """The built-in default scene, `hairjax/scenes/default.toml` (shipped as package data)."""
    return Path(__file__).parents[1] / "scenes" / "default.toml"


def load_scene(path: str | os.PathLike, overrides: Mapping[str, Any] | None = None) -> Scene:
    """Read a TOML scene file.

    Relative hair-file paths in `hair.source` are resolved against the scene file's
    directory; the scene's name defaults to the file's stem. `overrides` maps
    `"table.key"` (or `"name"`) to a value that replaces the file's (`hairjax … --set`);
    an override passes the same checks as the file's own keys.

    **Raises:** `SceneError`, naming the file and the offending `table.key`, for an
    unreadable file, invalid TOML, an unknown table or key, a value of the wrong type or
    out of range, or a hair file that is missing or malformed.
    """
    path = Path(path)
    try:
        with open(path, "rb") as f:
            data = tomllib.load(f)
    except OSError as e:
        raise SceneError(f"{path}: cannot read scene file: {e.strerror or e}") from e
    except UnicodeDecodeError as e:
        raise SceneError(f"{path}: scene file is not valid UTF-8 text: {e}") from e
    except tomllib.TOMLDecodeError as e:
        raise SceneError(f"{path}: invalid TOML: {e}") from e
    data = with_overrides(data, overrides or {}, str(path))
    # Resolve now so the scene does not depend on the working directory later.
    return scene_from_dict(data, path.resolve().parent, path.stem, source=str(path))


def scene_from_dict(
    data: Mapping[str, Any], base_dir: str | os.PathLike, name: str, *, source: str | None = None
) -> Scene:
    """Build a `Scene` from parsed TOML (a dict of tables).

    **Arguments:** `data`, the parsed file; `base_dir`, the directory relative hair paths
    are resolved against; `name`, the scene's name when `data` has no `name`; `source`,
    how to refer to the data in error messages (default: `name`).
    """
    where = source if source is not None else name
    if not isinstance(data, Mapping):
        raise SceneError(f"{where}: a scene must be a table of tables, got {describe(data)}")
    tables = _split_tables(data, where)

    scene_name = name
    if "name" in data:
        scene_name = data["name"]
        if not isinstance(scene_name, str) or not scene_name:
            raise SceneError(f"{where}: name must be a non-empty string, got {describe(scene_name)}")

    camera_args, framing = _read_camera(tables["camera"])
    camera = build(where, Camera, **camera_args)
    light = build(where, Light, **_read_light(tables["light"]))
    shading = _read_shading(where, tables["shading"])
    shadows = _read_method(
        where, tables["shadows"], "opacity-maps", shadow_method_names(), shadow_method_class
    )
    ordering = _read_method(where, tables["ordering"], "bins", ordering_names(), ordering_class)
    occluder = None
    if "occluder" in data:  # The table's presence, even empty, asks for an occluder.
        occluder = build(where, Occluder, **_read_occluder(tables["occluder"], Path(base_dir)))
    background = tables["background"].rgb("color")
    streaks = None
    if "streaks" in data:  # The table's presence, even empty, asks for streaks (§16).
        streaks = build(where, Streaks, **_read_streaks(tables["streaks"]))
    # Hair last: generating or reading it is the only slow step, so the cheap checks of
    # the other tables fail first.
    patches = read_patches(tables["hair"])
    strands = read_hair(tables["hair"], Path(base_dir))
    if framing is not None:  # eye, target and up from the hair (the table's size, fov, near)
        camera = build(
            where, _framed, strands=strands, camera=camera, near=camera_args.get("near"), framing=framing
        )

    reference = None
    if "reference" in data:
        reference = build(where, ReferenceSettings, **read_reference(tables["reference"]))
    scene_args = given(
        background=background,
        streaks=streaks,
        patches=patches,
        reference=reference,
        file_tables=_file_tables(data, Path(base_dir)),
    )
    return build(
        where,
        Scene,
        strands=strands,
        camera=camera,
        light=light,
        shading=shading,
        shadows=shadows,
        ordering=ordering,
        occluder=occluder,
        name=scene_name,
        **scene_args,
    )


# --------------------------------------------------------------------------- tables


def _file_tables(data: Mapping[str, Any], base_dir: Path) -> dict[str, dict[str, Any]]:
    """[hair] (without the patch keys, which `Scene.patches` holds; a file source as an
    absolute path) and [animation], as given: what `Scene.file_tables` keeps."""
    hair = {k: v for k, v in data.get("hair", {}).items() if k not in PATCH_KEYS}
    source = hair.get("source")
    if isinstance(source, str) and source not in PROCEDURAL_SOURCES:
        hair["source"] = str(Path(source) if Path(source).is_absolute() else (base_dir / source).resolve())
    tables = {"hair": hair}
    if "animation" in data:
        tables["animation"] = dict(data["animation"])
    return tables


def _split_tables(data: Mapping[str, Any], where: str) -> dict[str, Table]:
    """Check the top level (known tables, each a table, known keys) before reading values,
    so a typo is reported as such rather than as whatever its absence causes later."""
    known = scene_tables()
    for key, value in data.items():
        if key in TOP_LEVEL_KEYS:
            continue
        if key not in known:
            tables = ", ".join(f"[{t}]" for t in known)
            raise SceneError(
                f"{where}: unknown table or key {key!r}; allowed tables: {tables}; "
                f"top-level keys: {', '.join(TOP_LEVEL_KEYS)}"
            )
        if not isinstance(value, Mapping):
            raise SceneError(f"{where}: {key} must be a table ([{key}]), got {describe(value)}")
    return {name: Table(name, data.get(name, {}), where, keys) for name, keys in known.items()}


# --------------------------------------------------------------------------- readers


# camera.frame = "auto"'s keys: where the eye sits round and above the hair, and how close.
_FRAMING_KEYS = ("azimuth", "elevation", "zoom")


def _read_camera(table: Table) -> tuple[dict[str, Any], dict[str, Any] | None]:
    """The Camera's keyword arguments, and with `frame = "auto"` the framing's (azimuth,
    elevation, zoom: `frame_camera`'s), else None."""
    frame = table.choice("frame", CAMERA_FRAMES)
    if frame == "auto":
        # The framing sets these three; a given one would be silently replaced.
        for key in ("eye", "target", "up"):
            if key in table:
                raise SceneError(
                    f"{table.where}: camera.frame = 'auto' and camera.{key} exclude each other: "
                    f"the framing places the camera; remove one of them"
                )
    else:
        for key in _FRAMING_KEYS:
            if key in table:
                raise SceneError(f"{table.where}: camera.{key} applies only to frame = 'auto'")
    framing = given(
        azimuth=table.number("azimuth"),
        elevation=table.number("elevation", lo=-90, hi=90, lo_open=True, hi_open=True),
        zoom=table.number("zoom", lo=0, lo_open=True),
    )
    # Ranges (fov, sizes, near, eye != target, up) are Camera's checks.
    return given(
        eye=table.vec3("eye"),
        target=table.vec3("target"),
        up=table.vec3("up"),
        fov=table.number("fov"),
        width=table.integer("width"),
        height=table.integer("height"),
        near=table.number("near"),
    ), framing if frame == "auto" else None


def _framed(strands, camera: Camera, near: float | None, framing: Mapping[str, float]) -> Camera:
    """`frame_camera` for the strands, with the table's image size and fov (and near) and
    the framing's azimuth, elevation and zoom."""
    framed = frame_camera(strands, width=camera.width, height=camera.height, fov=camera.fov, **framing)
    return framed if near is None else dataclasses.replace(framed, near=near)


def _read_light(table: Table) -> dict[str, Any]:
    kind = table.choice("kind", LIGHT_KINDS) or "directional"
    # Light would silently drop the key that does not match its kind; say so instead.
    wrong, right = ("position", "direction") if kind == "directional" else ("direction", "position")
    if wrong in table:
        raise SceneError(
            f"{table.where}: light.{wrong} is not allowed for kind = {kind!r}; "
            f"a {kind} light takes light.{right}"
        )
    return given(
        kind=kind,
        direction=table.vec3("direction"),
        position=table.vec3("position"),
        color=table.rgb("color"),
    )


def _read_shading(where: str, table: Table):
    """[shading]: the registered model named by `model` (default Kajiya-Kay), read by its
    own `from_table`; a key of another model would be silently ignored, so it is refused."""
    cls = shading_model_class(table.choice("model", shading_model_names()) or "kajiya-kay")
    table.only_keys_of("model", cls.name, cls.table_keys)
    return build(where, cls.from_table, table=table)


def _read_method(where: str, table: Table, default: str, names, lookup):
    """[shadows] or [ordering]: the registered class named by `method`, built from its
    dataclass fields (their checks give the ranges)."""
    cls = lookup(table.choice("method", names) or default)
    table.only_keys_of("method", cls.method, field_names(cls))
    return build(where, cls, **table.options(cls))


def _read_streaks(table: Table) -> dict[str, Any]:
    # Ranges are Streaks' checks.
    return given(
        texels=table.integer("texels"),
        width=table.number("width"),
        contrast=table.number("contrast"),
        seed=table.integer("seed"),
    )


def _read_occluder(table: Table, base_dir: Path) -> dict[str, Any]:
    kind = table.choice("kind", OCCLUDER_KINDS) or "sphere"
    # Occluder would refuse the keys of the other kind; say which kind takes them.
    for key, owner in (("center", "sphere"), ("radius", "sphere"), ("path", "mesh")):
        if key in table and kind != owner:
            raise SceneError(f"{table.where}: occluder.{key} is only for kind = {owner!r}, not {kind!r}")
    path = table.string("path")
    if kind == "mesh":
        if path is None:
            raise SceneError(
                f"{table.where}: occluder.path is required for kind = 'mesh': "
                f"a {'/'.join(MESH_FILE_SUFFIXES)} file"
            )
        if Path(path).suffix.lower() not in MESH_FILE_SUFFIXES:
            raise table.error("path", f"a path to a {'/'.join(MESH_FILE_SUFFIXES)} file", path)
        full = Path(path) if Path(path).is_absolute() else base_dir / path
        if not full.is_file():
            raise SceneError(
                f"{table.where}: occluder.path file not found: {full} (from {path!r}; "
                "relative paths are resolved against the scene file's directory)"
            )
        path = str(full.resolve())
    return given(
        kind=kind,
        center=table.vec3("center"),
        radius=table.number("radius", lo=0, lo_open=True),
        color=table.rgb("color"),
        path=path,
    )


# --------------------------------------------------------------------------- helpers


def scene_for_hair(
    path: str | os.PathLike,
    *,
    width: int = 512,
    height: int = 512,
    overrides: Mapping[str, Any] | None = None,
) -> Scene:
    """A scene that shows the hair file at `path` (`.hair`, `.tfx` or `.ply`): what
    `hairjax render FILE` draws.

    It is the scene file `hair.source = path`, `camera.frame = "auto"` (`frame_camera`
    with a `width` × `height` image) with `overrides` (`"table.key" → value`, as
    `load_scene`'s, e.g. from `--set`) on top, so the strands are semi-transparent like a
    scene file's (alpha 0.5). Unless overridden: the ribbons are `_framing.WIDTH_FRACTION` (1/128)
    of the bounding radius wide in world units, the light is the camera's `key_light` (`_framing.py`),
    and an override of camera.eye, target or up replaces the framing. The name is the
    file's stem. Raises `HairFormatError` for a file that cannot be read, `SceneError`
    for a bad override.
    """
    path = Path(path)
    overrides = dict(overrides or {})
    camera: dict[str, Any] = {"width": width, "height": height}
    if not any(f"camera.{key}" in overrides for key in ("eye", "target", "up")):
        camera["frame"] = "auto"
    data = with_overrides({"hair": {"source": str(path.resolve())}, "camera": camera}, overrides, str(path))
    scene = scene_from_dict(data, path.resolve().parent, path.stem, source=str(path))
    if not any(key.startswith("hair.width") for key in overrides):
        _, radius = bounding_sphere(scene.strands.points)
        # Fires when every point coincides: frame_camera then frames one world unit.
        radius = radius if radius > 0 else 1.0
        ribbon = WIDTH_FRACTION * radius
        strands = scene.strands.replace(width=np.full(scene.strands.num_strands, ribbon), width_units="world")
        tables = dict(scene.file_tables or {})
        tables["hair"] = {**tables.get("hair", {}), "width": ribbon, "width_units": "world"}
        scene = scene.replace(strands=strands, file_tables=tables)
    if not any(key.startswith("light.") for key in overrides):
        scene = scene.replace(light=key_light(scene.camera))
    return scene
