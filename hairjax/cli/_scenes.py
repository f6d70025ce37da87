"""A command's scene: a TOML file or a bare hair file, with --set, --seed and --size applied.

`--set table.key=value` reads `value` as TOML (`0.3`, `[1, 0, 0]`, `true`, `"furball"`);
text that is not TOML is taken as a string, so `--set hair.source=furball` works. Every
override then passes the scene file's own checks (`load_scene(path, overrides)`), so a
typo names the key and the allowed ones. A hair file (any suffix of hairjax/_io's
`FORMATS`) given where a scene is expected is framed automatically (`[camera] frame =
"auto"`, docs/scenes.md); any other suffix but .toml is an unknown file type.
"""

from __future__ import annotations

import argparse
import tomllib
from pathlib import Path
from typing import Any

from .._scene._hair_table import HAIR_FILE_SUFFIXES  # the suffixes the scene reader takes as hair files

__all__ = ["scene_overrides", "load_cli_scene", "scene_path"]


def _toml_value(text: str) -> Any:
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text  # not a TOML value: a bare string, e.g. furball


def scene_path(path: Path | None) -> Path:
    """The scene a command reads: `path`, or the built-in default scene."""
    from .._scene._file import default_scene_path

    return default_scene_path() if path is None else path


def _camera_size(path: Path, overrides: dict[str, Any]) -> tuple[int, int]:
    """The camera's width and height before --size: from --set, the file, or the default."""
    from .._scene._camera import Camera

    camera: dict[str, Any] = {}
    if path.suffix.lower() not in HAIR_FILE_SUFFIXES:
        try:
            camera = tomllib.loads(path.read_text()).get("camera", {})
        except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError, AttributeError):
            camera = {}  # unreadable: load_scene reports it, with the file's name
    if not isinstance(camera, dict):
        camera = {}
    sizes = []
    for key in ("width", "height"):
        value = overrides.get(f"camera.{key}", camera.get(key, getattr(Camera(), key)))
        sizes.append(value if isinstance(value, int) and value > 0 else getattr(Camera(), key))
    return sizes[0], sizes[1]


def scene_overrides(args: argparse.Namespace, path: Path) -> dict[str, Any]:
    """`table.key → value` from --set, then --seed and --size (which win over --set)."""
    overrides = {key: _toml_value(value) for key, value in getattr(args, "overrides", [])}
    if getattr(args, "seed", None) is not None:
        overrides["hair.seed"] = args.seed
    size = getattr(args, "size", None)
    if size is not None:
        width, height = size
        if height is None:  # W alone: keep the scene's aspect ratio
            w0, h0 = _camera_size(path, overrides)
            height = max(1, round(width * h0 / w0))
        overrides["camera.width"], overrides["camera.height"] = width, height
    return overrides


def load_cli_scene(args: argparse.Namespace, path: Path | None):
    """The scene at `path` (default: built-in) with the command line's overrides."""
    from .._scene._file import load_scene

    path = scene_path(path)
    if path.suffix and path.suffix.lower() not in (".toml",) + HAIR_FILE_SUFFIXES:
        from .._errors import SceneError

        known = ", ".join(HAIR_FILE_SUFFIXES)
        raise SceneError(
            f"{path}: unknown file type {path.suffix!r} (known: .toml scenes; hair files {known})"
        )
    overrides = scene_overrides(args, path)
    if path.suffix.lower() in HAIR_FILE_SUFFIXES:
        from .._scene._file import scene_for_hair

        return scene_for_hair(path, overrides=overrides)
    return load_scene(path, overrides)
