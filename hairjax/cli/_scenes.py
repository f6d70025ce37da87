"""A command's scene: a TOML file or a bare hair file, with --set, --unset, --seed and
--size applied.

`--set table.key=value` reads `value` as TOML (`0.3`, `[1, 0, 0]`, `true`, `"furball"`);
text that is not TOML is taken as a string, so `--set hair.source=furball` works.
`--unset table.key` removes a key, so its default applies. Every change then passes the
scene file's own checks (`load_scene(path, overrides)`), so a typo names the key and the
allowed ones; an error about a key the command line set names the option (`--set
shading.kd=-1: …`, `--size 0x5: …`), not the file. Setting `shading.model`,
`shadows.method` or `ordering.method` drops the file's keys the new choice does not read,
with a warning naming them. A hair file (any suffix of hairjax/_io's `FORMATS`) given where a
scene is expected is framed automatically (`[camera] frame = "auto"`, docs/scenes.md);
any other suffix but .toml is an unknown file type.
"""

from __future__ import annotations

import argparse
import contextlib
import tomllib
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

from .._scene._hair_table import HAIR_FILE_SUFFIXES  # the suffixes the scene reader takes as hair files

__all__ = [
    "scene_overrides",
    "scene_origins",
    "recorded_changes",
    "load_cli_scene",
    "scene_path",
    "options_blamed",
]


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
    from .._values._camera import Camera

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


def _unset(args: argparse.Namespace) -> list[str]:
    from .._errors import SceneError

    unset = list(getattr(args, "unset", []))
    both = [key for key, _ in getattr(args, "overrides", []) if key in unset]
    if both:
        raise SceneError(f"--set {both[0]}=… and --unset {both[0]} exclude each other")
    return unset


def scene_overrides(args: argparse.Namespace, path: Path) -> dict[str, Any]:
    """`table.key → value` from --set and --unset (the value `UNSET`), then --seed and
    --size (which win over --set)."""
    from .._scene._file import UNSET

    overrides = {key: _toml_value(value) for key, value in getattr(args, "overrides", [])}
    overrides.update(dict.fromkeys(_unset(args), UNSET))
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


def scene_origins(args: argparse.Namespace) -> dict[str, str]:
    """`table.key → the option that set it`, as error messages name it."""
    origins = {key: f"--set {key}={value}" for key, value in getattr(args, "overrides", [])}
    origins.update({key: f"--unset {key}" for key in getattr(args, "unset", [])})
    if getattr(args, "seed", None) is not None:
        origins["hair.seed"] = f"--seed {args.seed}"
    size = getattr(args, "size", None)
    if size is not None:
        text = f"--size {size[0]}" + ("" if size[1] is None else f"x{size[1]}")
        origins["camera.width"] = origins["camera.height"] = text
    return origins


def recorded_changes(args: argparse.Namespace, path: Path) -> dict[str, Any]:
    """`scene_overrides` as a sidecar records them: a removed key as None."""
    from .._scene._file import UNSET

    return {k: None if v is UNSET else v for k, v in scene_overrides(args, path).items()}


@contextlib.contextmanager
def options_blamed(path: Path, origins: Mapping[str, str]) -> Iterator[None]:
    """Inside, a `SceneError` about a key the command line set names the option
    (`origins`), not the scene file `path`."""
    from .._errors import SceneError
    from .._scene._file import blamed_on

    try:
        yield
    except SceneError as err:
        blamed = blamed_on(err, str(path), origins)
        if blamed is err:
            raise
        raise blamed from None


def load_cli_scene(args: argparse.Namespace, path: Path | None):
    """The scene at `path` (default: built-in) with the command line's changes."""
    from .._scene._file import load_scene

    path = scene_path(path)
    if path.suffix and path.suffix.lower() not in (".toml",) + HAIR_FILE_SUFFIXES:
        from .._errors import SceneError

        known = ", ".join(HAIR_FILE_SUFFIXES)
        raise SceneError(
            f"{path}: unknown file type {path.suffix!r} (known: .toml scenes; hair files {known})"
        )
    with options_blamed(path, scene_origins(args)):
        overrides = scene_overrides(args, path)
        if path.suffix.lower() in HAIR_FILE_SUFFIXES:
            from .._scene._file import scene_for_hair

            return scene_for_hair(path, overrides=overrides)
        return load_scene(path, overrides)
