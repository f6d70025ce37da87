"""Scene files: TOML text -> `Scene`.

A scene file has one table per part of the scene (`[hair]`, `[camera]`, `[light]`,
`[shading]`, `[shadows]`, `[ordering]`, `[occluder]`, `[background]`, `[streaks]`,
`[animation]`) and an optional
top-level `name`; docs/scenes.md documents every key. Every key but `hair.source` is
optional, and an absent key takes the default of the dataclass (or generator) it feeds,
so defaults live in one place.

Errors: everything wrong with a file raises a single `SceneError` whose message starts
with the file path and names the key as `table.key`, what is allowed, and what was found.
Types are checked here, before any dataclass sees a value, because NumPy would happily turn
`true` into 1.0 or `"3"` into 3.0; value ranges that the dataclasses in `_scene.py`
already check are left to them, and their errors are re-raised with the file path.
"""

from __future__ import annotations

import math
import os
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ._errors import SceneError
from ._lookup import LOOKUP_MODELS
from ._scene import (
    MODELS,
    OCCLUDER_KINDS,
    ORDERING_METHODS,
    SHADOW_METHODS,
    Camera,
    Light,
    Occluder,
    Ordering,
    PatchGeometry,
    Scene,
    Shadows,
)
from ._scheuermann import ScheuermannMaps, ScheuermannParams
from ._shading import ShadingParams
from ._sources import furball, scalp
from ._strands import WIDTH_UNITS, Strands
from ._streaks import Streaks

__all__ = ["load_scene", "scene_from_dict", "default_scene_path"]

PROCEDURAL_SOURCES = ("furball", "scalp")
HAIR_FILE_SUFFIXES = (".hair", ".tfx", ".ply")
LIGHT_KINDS = ("directional", "point")
MESH_FILE_SUFFIXES = (".obj",)

# Defaults that belong to the file format rather than to a dataclass: a scene's hair is
# semi-transparent unless the file says otherwise, whatever its source.
DEFAULT_HAIR_ALPHA = 0.5
DEFAULT_HAIR_WIDTH = 1.0

# [hair] keys by the sources that accept them.
_HAIR_COMMON = ("source", "alpha", "width", "width_units", "scale", "translate", "color",
                "geometry", "patch_width", "opaque_core")
HAIR_GEOMETRIES = ("strands", "patches")
_HAIR_PROCEDURAL = ("strands", "points", "seed", "length", "gravity")
_HAIR_ONLY_FOR = {"inertia": "furball", "radius": "scalp", "coverage": "scalp"}

# [shading] keys by the models that accept them (the rest are common: model, kd, kappa, ambient).
_SHADING_KAJIYA_KAY = ("ks", "shininess")
_SHADING_SCHEUERMANN = ("primary_color", "primary_exponent", "primary_shift", "secondary_color",
                        "secondary_exponent", "secondary_shift", "normal_center", "texture_seed",
                        "shift_noise", "mask_noise", "base_texture", "alpha_texture", "occlusion",
                        "hair_occlusion")

TABLES: dict[str, tuple[str, ...]] = {
    "hair": _HAIR_COMMON + _HAIR_PROCEDURAL + tuple(_HAIR_ONLY_FOR),
    "camera": ("eye", "target", "up", "fov", "width", "height", "near"),
    "light": ("kind", "direction", "position", "color"),
    "shading": ("model", "kd", "ks", "shininess", "kappa", "ambient", "lookup_size") + _SHADING_SCHEUERMANN,
    "shadows": ("method", "maps", "resolution"),
    "ordering": ("method", "bins"),
    "occluder": ("kind", "center", "radius", "color", "path"),
    "background": ("color",),
    "streaks": ("texels", "width", "contrast", "seed"),
    # Read by `hairjax animate` only (hairjax/_animate.py); a still render shows the rest pose.
    "animation": ("amplitude", "frequency", "phase", "inertia", "frames"),
}
TOP_LEVEL_KEYS = ("name",)


def default_scene_path() -> Path:
    """The built-in default scene, `hairjax/scenes/default.toml` (shipped as package data)."""
    return Path(__file__).parent / "scenes" / "default.toml"


def load_scene(path: str | os.PathLike) -> Scene:
    """Read a TOML scene file.

    Relative hair-file paths in `hair.source` are resolved against the scene file's
    directory; the scene's name defaults to the file's stem.

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
        raise SceneError(f"{where}: a scene must be a table of tables, got {_describe(data)}")
    tables = _split_tables(data, where)

    scene_name = name
    if "name" in data:
        scene_name = data["name"]
        if not isinstance(scene_name, str) or not scene_name:
            raise SceneError(
                f"{where}: name must be a non-empty string, got {_describe(scene_name)}")

    camera = _build(where, Camera, **_read_camera(tables["camera"]))
    light = _build(where, Light, **_read_light(tables["light"]))
    model, params, maps = _read_shading(tables["shading"])
    lookup_size = _read_lookup_size(tables["shading"], model)
    shadows = _build(where, Shadows, **_read_shadows(tables["shadows"]))
    ordering = _build(where, Ordering, **_read_ordering(tables["ordering"]))
    occluder = None
    if "occluder" in data:  # The table's presence, even empty, asks for an occluder.
        occluder = _build(where, Occluder, **_read_occluder(tables["occluder"], Path(base_dir)))
    background = tables["background"].rgb("color")
    streaks = None
    if "streaks" in data:  # The table's presence, even empty, asks for streaks (§16).
        streaks = _build(where, Streaks, **_read_streaks(tables["streaks"]))
    # Hair last: generating or reading it is the only slow step, so the cheap checks of
    # the other tables fail first.
    patches = _read_patches(tables["hair"])
    strands = _read_hair(tables["hair"], Path(base_dir))

    scene_args = _given(shading_model=model, background=background, lookup_size=lookup_size,
                        streaks=streaks, scheuermann_maps=maps, patches=patches)
    return _build(where, Scene, strands=strands, camera=camera, light=light, params=params,
                  shadows=shadows, ordering=ordering, occluder=occluder, name=scene_name,
                  **scene_args)


# --------------------------------------------------------------------------- tables


def _split_tables(data: Mapping[str, Any], where: str) -> dict[str, _Table]:
    """Check the top level (known tables, each a table, known keys) before reading values,
    so a typo is reported as such rather than as whatever its absence causes later."""
    for key, value in data.items():
        if key in TOP_LEVEL_KEYS:
            continue
        if key not in TABLES:
            tables = ", ".join(f"[{t}]" for t in TABLES)
            raise SceneError(f"{where}: unknown table or key {key!r}; allowed tables: {tables}; "
                             f"top-level keys: {', '.join(TOP_LEVEL_KEYS)}")
        if not isinstance(value, Mapping):
            raise SceneError(f"{where}: {key} must be a table ([{key}]), got {_describe(value)}")
    return {name: _Table(name, data.get(name, {}), where) for name in TABLES}


class _Table:
    """One TOML table being read.

    Each getter returns `None` for an absent key (so the consumer's default applies) and
    otherwise a checked Python value; every failure is a `SceneError` naming `table.key`.
    """

    def __init__(self, name: str, data: Mapping[str, Any], where: str):
        self.name = name
        self.data = data
        self.where = where
        allowed = TABLES[name]
        for key in data:
            if key not in allowed:
                raise SceneError(f"{where}: unknown key {name}.{key}; allowed keys in "
                                 f"[{name}]: {', '.join(allowed)}")

    def __contains__(self, key: str) -> bool:
        return key in self.data

    def error(self, key: str, requirement: str, value: Any) -> SceneError:
        return SceneError(f"{self.where}: {self.name}.{key} must be {requirement}, "
                          f"got {_describe(value)}")

    def number(self, key: str, *, lo: float | None = None, hi: float | None = None,
               lo_open: bool = False, hi_open: bool = False) -> float | None:
        """A finite number (TOML integer or float, not boolean), optionally in a range."""
        if key not in self.data:
            return None
        value = self.data[key]
        if not _is_number(value) or not math.isfinite(value):
            raise self.error(key, "a finite number", value)
        requirement = _range_text(lo, hi, lo_open, hi_open)
        if not _in_range(value, lo, hi, lo_open, hi_open):
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
        if not (isinstance(value, list) and len(value) == 3
                and all(_is_number(x) and math.isfinite(x) for x in value)):
            raise self.error(key, "an array of 3 finite numbers", value)
        return tuple(float(x) for x in value)

    def rgb(self, key: str, *, scalar: bool = False) -> Any:
        """A colour: an array of 3 numbers >= 0 (or, with `scalar`, also one number >= 0,
        which the consumer broadcasts to RGB)."""
        if key not in self.data:
            return None
        value = self.data[key]
        allowed = "a number >= 0 or an array of 3 numbers >= 0" if scalar \
            else "an array of 3 numbers >= 0 (RGB)"
        if scalar and _is_number(value):
            items = [value]
        elif isinstance(value, list) and len(value) == 3:
            items = value
        else:
            raise self.error(key, allowed, value)
        if not all(_is_number(x) and math.isfinite(x) and x >= 0 for x in items):
            raise self.error(key, allowed, value)
        if isinstance(value, list):
            return tuple(float(x) for x in value)
        return float(value)


# --------------------------------------------------------------------------- readers


def _read_hair(table: _Table, base_dir: Path) -> Strands:
    """[hair]: a procedural generator or a hair file, then scale/translate/color."""
    where = table.where
    source = table.string("source")
    if source is None:
        raise SceneError(f"{where}: hair.source is required: 'furball', 'scalp', or a path "
                         f"to a {'/'.join(HAIR_FILE_SUFFIXES)} file")
    is_file = source not in PROCEDURAL_SOURCES
    if is_file and Path(source).suffix.lower() not in HAIR_FILE_SUFFIXES:
        raise table.error("source", "'furball', 'scalp', or a path to a "
                          f"{'/'.join(HAIR_FILE_SUFFIXES)} file", source)
    _check_hair_keys(table, source, is_file)

    alpha = table.number("alpha", lo=0, hi=1, lo_open=True)
    width = table.number("width", lo=0, lo_open=True)
    scale = table.number("scale", lo=0, lo_open=True)
    translate = table.vec3("translate")
    color = table.rgb("color")
    alpha = DEFAULT_HAIR_ALPHA if alpha is None else alpha
    width = DEFAULT_HAIR_WIDTH if width is None else width

    if is_file:
        strands = _load_hair_file(table, source, base_dir, alpha, width)
    else:
        strands = _generate_hair(table, source, alpha, width)

    if scale is not None or translate is not None:
        strands = strands.transformed(1.0 if scale is None else scale,
                                      (0.0, 0.0, 0.0) if translate is None else translate)
    if color is not None:
        strands = strands.replace(color=color)  # Strands broadcasts it to every point.
    units = table.choice("width_units", WIDTH_UNITS)
    if units is not None:  # `width` is then in the scene's units, after `scale`
        strands = strands.replace(width_units=units)
    return strands


def _read_patches(table: _Table) -> PatchGeometry | None:
    """[hair] geometry = "patches" with patch_width (required) and opaque_core (§18)."""
    geometry = table.choice("geometry", HAIR_GEOMETRIES)
    width = table.number("patch_width", lo=0, lo_open=True)
    core = table.number("opaque_core", lo=0, hi=1)
    if geometry != "patches":
        for key in ("patch_width", "opaque_core"):
            if key in table:
                raise SceneError(f"{table.where}: hair.{key} applies only to geometry = 'patches'")
        return None
    if width is None:
        raise SceneError(f"{table.where}: hair.patch_width (world units) is required with "
                         "geometry = 'patches'")
    return PatchGeometry(width, **_given(opaque_core=core))


def _check_hair_keys(table: _Table, source: str, is_file: bool) -> None:
    """Reject keys that the chosen source would silently ignore."""
    for key in table.data:
        if is_file and (key in _HAIR_PROCEDURAL or key in _HAIR_ONLY_FOR):
            raise SceneError(
                f"{table.where}: hair.{key} applies only to procedural sources "
                f"({', '.join(repr(s) for s in PROCEDURAL_SOURCES)}), not to the hair file "
                f"{source!r}; allowed keys for a file: {', '.join(_HAIR_COMMON)}")
        only_for = _HAIR_ONLY_FOR.get(key)
        if not is_file and only_for is not None and only_for != source:
            raise SceneError(f"{table.where}: hair.{key} applies only to source = "
                             f"{only_for!r}, not {source!r}")


def _generate_hair(table: _Table, source: str, alpha: float, width: float) -> Strands:
    """Call `furball` or `scalp` with the keys given (their own defaults for the rest)."""
    kwargs = _given(
        strands=table.integer("strands", lo=1),
        points=table.integer("points", lo=2),
        seed=table.integer("seed", lo=0),
        length=table.number("length", lo=0, lo_open=True),
        gravity=table.vec3("gravity"),
    )
    if source == "furball":
        kwargs.update(_given(inertia=table.vec3("inertia")))
        return furball(**kwargs, alpha=alpha, width=width)
    kwargs.update(_given(radius=table.number("radius", lo=0, lo_open=True),
                         coverage=table.number("coverage", lo=0, hi=1, lo_open=True)))
    return scalp(**kwargs, alpha=alpha, width=width)


def _load_hair_file(table: _Table, source: str, base_dir: Path, alpha: float,
                    width: float) -> Strands:
    """Read a .hair/.tfx/.ply file; a relative path is relative to the scene's directory."""
    path = Path(source)
    if not path.is_absolute():
        path = base_dir / path
    if not path.is_file():
        raise SceneError(f"{table.where}: hair.source file not found: {path} (from "
                         f"{source!r}; relative paths are resolved against the scene "
                         "file's directory)")
    from ._io import load_hair  # Lazy: only file sources need the readers.

    try:
        return load_hair(path, alpha=alpha, width=width)
    except (OSError, ValueError) as e:  # ValueError includes HairFormatError.
        raise SceneError(f"{table.where}: hair.source could not be loaded: {e}") from e


def _read_camera(table: _Table) -> dict[str, Any]:
    # Ranges (fov, sizes, near, eye != target, up) are Camera's checks.
    return _given(eye=table.vec3("eye"), target=table.vec3("target"), up=table.vec3("up"),
                  fov=table.number("fov"), width=table.integer("width"),
                  height=table.integer("height"), near=table.number("near"))


def _read_light(table: _Table) -> dict[str, Any]:
    kind = table.choice("kind", LIGHT_KINDS) or "directional"
    # Light would silently drop the key that does not match its kind; say so instead.
    wrong, right = ("position", "direction") if kind == "directional" else ("direction", "position")
    if wrong in table:
        raise SceneError(f"{table.where}: light.{wrong} is not allowed for kind = {kind!r}; "
                         f"a {kind} light takes light.{right}")
    return _given(kind=kind, direction=table.vec3("direction"),
                  position=table.vec3("position"), color=table.rgb("color"))


def _read_shading(table: _Table):
    # ShadingParams does not validate (it is a pytree that gradients flow through), so the
    # ranges are checked here.
    model = table.choice("model", MODELS)
    # Keys of the other model would be silently ignored: say so instead.
    other = _SHADING_KAJIYA_KAY if model == "scheuermann" else _SHADING_SCHEUERMANN
    for key in table.data:
        if key in other:
            raise SceneError(f"{table.where}: shading.{key} is not a key of model = "
                             f"{model or 'kajiya-kay'!r}")
    if model == "scheuermann":
        return model, *_read_scheuermann(table)
    params = ShadingParams(**_given(
        kd=table.rgb("kd", scalar=True),
        ks=table.rgb("ks", scalar=True),
        shininess=table.number("shininess", lo=0, lo_open=True),
        kappa=table.number("kappa", lo=0),
        ambient=table.rgb("ambient", scalar=True),
    ))
    return model, params, None


def _read_scheuermann(table: _Table) -> tuple[ScheuermannParams, ScheuermannMaps]:
    """[shading] with model = "scheuermann" (docs/model.md §17)."""
    params = ScheuermannParams(**_given(
        kd=table.rgb("kd", scalar=True),
        ambient=table.rgb("ambient", scalar=True),
        kappa=table.number("kappa", lo=0),
        primary_color=table.rgb("primary_color", scalar=True),
        primary_exponent=table.number("primary_exponent", lo=0, lo_open=True),
        primary_shift=table.number("primary_shift"),
        secondary_color=table.rgb("secondary_color", scalar=True),
        secondary_exponent=table.number("secondary_exponent", lo=0, lo_open=True),
        secondary_shift=table.number("secondary_shift"),
    ))
    # Types here (TOML booleans are not numbers); ranges are ScheuermannMaps' checks.
    for key, rgb in (("base_texture", True), ("alpha_texture", False), ("occlusion", False)):
        value = table.data.get(key)
        if value is None:
            continue
        rows = value if isinstance(value, list) else None
        items = [x for row in rows for x in (row if isinstance(row, list) else [None])] \
            if rgb and rows is not None else rows
        if not rows or not all(_is_number(x) for x in items) \
                or (rgb and not all(len(row) == 3 for row in rows)):
            raise table.error(key, "a non-empty array of [r, g, b] arrays" if rgb
                              else "a non-empty array of numbers", value)
    maps = _given(
        normal_center=table.vec3("normal_center"),
        texture_seed=table.integer("texture_seed", lo=0),
        shift_noise=table.number("shift_noise", lo=0),
        mask_noise=table.number("mask_noise", lo=0, hi=1),
        base_texture=table.data.get("base_texture"),
        alpha_texture=table.data.get("alpha_texture"),
        occlusion=table.data.get("occlusion"),
        hair_occlusion=table.number("hair_occlusion", lo=0),
    )
    try:
        return params, ScheuermannMaps(**maps)
    except SceneError as e:  # the tables' checks (ScheuermannMaps): add the file path
        raise SceneError(f"{table.where}: {e}") from e


def _read_lookup_size(table: _Table, model: str | None) -> int | None:
    # Range is Scene's check; a table size for an analytic model would be silently ignored.
    if "lookup_size" in table and model not in LOOKUP_MODELS:
        raise SceneError(f"{table.where}: shading.lookup_size applies only to the lookup models "
                         f"({', '.join(repr(m) for m in LOOKUP_MODELS)}), not to model = "
                         f"{model or 'kajiya-kay'!r}")
    return table.integer("lookup_size")


def _read_streaks(table: _Table) -> dict[str, Any]:
    # Ranges are Streaks' checks.
    return _given(texels=table.integer("texels"), width=table.number("width"),
                  contrast=table.number("contrast"), seed=table.integer("seed"))


def _read_shadows(table: _Table) -> dict[str, Any]:
    # Ranges of maps and resolution are Shadows' checks.
    return _given(method=table.choice("method", SHADOW_METHODS),
                  maps=table.integer("maps"), resolution=table.integer("resolution"))


def _read_ordering(table: _Table) -> dict[str, Any]:
    return _given(method=table.choice("method", ORDERING_METHODS), bins=table.integer("bins"))


def _read_occluder(table: _Table, base_dir: Path) -> dict[str, Any]:
    kind = table.choice("kind", OCCLUDER_KINDS) or "sphere"
    # Occluder would refuse the keys of the other kind; say which kind takes them.
    for key, owner in (("center", "sphere"), ("radius", "sphere"), ("path", "mesh")):
        if key in table and kind != owner:
            raise SceneError(f"{table.where}: occluder.{key} is only for kind = {owner!r}, "
                             f"not {kind!r}")
    path = table.string("path")
    if kind == "mesh":
        if path is None:
            raise SceneError(f"{table.where}: occluder.path is required for kind = 'mesh': "
                             f"a {'/'.join(MESH_FILE_SUFFIXES)} file")
        if Path(path).suffix.lower() not in MESH_FILE_SUFFIXES:
            raise table.error("path", f"a path to a {'/'.join(MESH_FILE_SUFFIXES)} file", path)
        full = Path(path) if Path(path).is_absolute() else base_dir / path
        if not full.is_file():
            raise SceneError(f"{table.where}: occluder.path file not found: {full} (from {path!r}; "
                             "relative paths are resolved against the scene file's directory)")
        path = str(full.resolve())
    return _given(kind=kind, center=table.vec3("center"),
                  radius=table.number("radius", lo=0, lo_open=True), color=table.rgb("color"),
                  path=path)


# --------------------------------------------------------------------------- helpers


def _build(where: str, factory, **kwargs):
    """Construct a scene dataclass; its own SceneError gains the file path."""
    try:
        return factory(**kwargs)
    except SceneError as e:
        raise SceneError(f"{where}: {e}") from e


def _given(**kwargs) -> dict[str, Any]:
    """The keyword arguments whose value is not None (i.e. keys present in the file)."""
    return {k: v for k, v in kwargs.items() if v is not None}


def _is_number(value: Any) -> bool:
    # bool is an int subclass in Python, but `true` is not a number in a scene file.
    return isinstance(value, int | float) and not isinstance(value, bool)


def _in_range(value: float, lo, hi, lo_open: bool, hi_open: bool) -> bool:
    if lo is not None and (value <= lo if lo_open else value < lo):
        return False
    if hi is not None and (value >= hi if hi_open else value > hi):
        return False
    return True


def _range_text(lo, hi, lo_open: bool, hi_open: bool) -> str:
    """'> 0', '>= 0', 'in (0, 1]', ... for error messages."""
    if lo is not None and hi is not None:
        return f"in {'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'}"
    if lo is not None:
        return f"{'>' if lo_open else '>='} {lo:g}"
    if hi is not None:
        return f"{'<' if hi_open else '<='} {hi:g}"
    return "a finite number"


def _toml_type(value: Any) -> str:
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


def _show(value: Any) -> str:
    """A value roughly as TOML writes it (true, not True)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, list):
        return "[" + ", ".join(_show(x) for x in value) + "]"
    if isinstance(value, Mapping):
        return "{" + ", ".join(f"{k} = {_show(v)}" for k, v in value.items()) + "}"
    return repr(value)


def _describe(value: Any) -> str:
    """A value for an error message. Numbers are shown bare ('got -1'); other types also
    name their TOML type, since '"3"' and '3' look alike to a reader skimming the message."""
    if _is_number(value):
        return _show(value)
    return f"{_show(value)} ({_toml_type(value)})"
