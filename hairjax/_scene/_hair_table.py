"""The [hair] table of a scene file: a procedural generator or a hair file, then scale,
translate, colour and width units, and the hair-patch geometry (docs/scenes.md)."""

from __future__ import annotations

from pathlib import Path

from .._errors import SceneError
from .._io import FORMATS
from .._values._strands import WIDTH_UNITS, Strands
from ._procedural import combed, furball, scalp
from ._scene import PatchGeometry
from ._table import Table, given

__all__ = ["read_hair", "read_patches", "HAIR_KEYS", "HAIR_FILE_SUFFIXES", "PROCEDURAL_SOURCES"]

PROCEDURAL_SOURCES = ("furball", "scalp", "combed")
HAIR_FILE_SUFFIXES = tuple(FORMATS)  # every format hairjax/_io reads

# Defaults that belong to the file format rather than to a dataclass: a scene's hair is
# semi-transparent unless the file says otherwise, whatever its source.
DEFAULT_HAIR_ALPHA = 0.5
DEFAULT_HAIR_WIDTH = 1.0

# [hair] keys by the sources that accept them.
_HAIR_COMMON = (
    "source",
    "alpha",
    "width",
    "width_units",
    "scale",
    "translate",
    "color",
    "geometry",
    "patch_width",
    "opaque_core",
    "patch_strands",
    "patch_strand_alpha",
    "patch_strand_tips",
)
HAIR_GEOMETRIES = ("strands", "patches")
_HAIR_PROCEDURAL = ("strands", "points", "seed", "length")
_HAIR_ONLY_FOR = {
    "gravity": ("furball", "scalp"),
    "inertia": ("furball",),
    "radius": ("scalp", "combed"),
    "coverage": ("scalp",),
    "layers": ("combed",),
}

HAIR_KEYS = _HAIR_COMMON + _HAIR_PROCEDURAL + tuple(_HAIR_ONLY_FOR)


def read_hair(table: Table, base_dir: Path) -> Strands:
    """[hair]: a procedural generator or a hair file, then scale/translate/color."""
    where = table.where
    source = table.string("source")
    if source is None:
        raise SceneError(
            f"{where}: hair.source is required: 'furball', 'scalp', 'combed', or a path "
            f"to a {'/'.join(HAIR_FILE_SUFFIXES)} file"
        )
    is_file = source not in PROCEDURAL_SOURCES
    if is_file and Path(source).suffix.lower() not in HAIR_FILE_SUFFIXES:
        raise table.error(
            "source",
            f"'furball', 'scalp', 'combed', or a path to a {'/'.join(HAIR_FILE_SUFFIXES)} file",
            source,
        )
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
        try:
            strands = _generate_hair(table, source, alpha, width)
        except SceneError:
            raise
        except ValueError as e:  # e.g. a length that takes points beyond the coordinate bound
            raise SceneError(f"{where}: the {source!r} hair: {e}") from e

    if scale is not None or translate is not None:
        try:
            strands = strands.transformed(
                1.0 if scale is None else scale, (0.0, 0.0, 0.0) if translate is None else translate
            )
        except ValueError as e:  # a point moved beyond the coordinate bound (docs/scenes.md)
            raise SceneError(f"{where}: after hair.scale and hair.translate, {e}") from e
    if color is not None:
        strands = strands.replace(color=color)  # Strands broadcasts it to every point.
    units = table.choice("width_units", WIDTH_UNITS)
    if units is not None:  # `width` is then in the scene's units, after `scale`
        strands = strands.replace(width_units=units)
    return strands


def read_patches(table: Table) -> PatchGeometry | None:
    """[hair] geometry = "patches" with patch_width (required), opaque_core and the strand
    texture's patch_strands, patch_strand_alpha, patch_strand_tips (§18)."""
    geometry = table.choice("geometry", HAIR_GEOMETRIES)
    width = table.number("patch_width", lo=0, lo_open=True)
    core = table.number("opaque_core", lo=0, hi=1)
    strands = table.integer("patch_strands", lo=1)
    strand_alpha = table.number("patch_strand_alpha", lo=0, hi=1)
    tips = table.number("patch_strand_tips", lo=0, hi=1)
    if geometry != "patches":
        for key in ("patch_width", "opaque_core", "patch_strands", "patch_strand_alpha", "patch_strand_tips"):
            if key in table:
                raise SceneError(f"{table.where}: hair.{key} applies only to geometry = 'patches'")
        return None
    if width is None:
        raise SceneError(
            f"{table.where}: hair.patch_width (world units) is required with geometry = 'patches'"
        )
    return PatchGeometry(
        width, **given(opaque_core=core, strands=strands, strand_alpha=strand_alpha, tips=tips)
    )


def _check_hair_keys(table: Table, source: str, is_file: bool) -> None:
    """Reject keys that the chosen source would silently ignore."""
    for key in table.data:
        if is_file and (key in _HAIR_PROCEDURAL or key in _HAIR_ONLY_FOR):
            raise SceneError(
                f"{table.where}: hair.{key} applies only to procedural sources "
                f"({', '.join(repr(s) for s in PROCEDURAL_SOURCES)}), not to the hair file "
                f"{source!r}; allowed keys for a file: {', '.join(_HAIR_COMMON)}"
            )
        only_for = _HAIR_ONLY_FOR.get(key)
        if not is_file and only_for is not None and source not in only_for:
            sources = " or ".join(repr(s) for s in only_for)
            raise SceneError(f"{table.where}: hair.{key} applies only to source = {sources}, not {source!r}")


def _generate_hair(table: Table, source: str, alpha: float, width: float) -> Strands:
    """Call `furball`, `scalp` or `combed` with the keys given (their own defaults for the
    rest)."""
    kwargs = given(
        strands=table.integer("strands", lo=1),
        points=table.integer("points", lo=2),
        seed=table.integer("seed", lo=0),
        length=table.number("length", lo=0, lo_open=True),
    )
    if source == "combed":
        kwargs.update(
            given(radius=table.number("radius", lo=0, lo_open=True), layers=table.integer("layers", lo=1))
        )
        return combed(**kwargs, alpha=alpha, width=width)
    kwargs.update(given(gravity=table.vec3("gravity")))
    if source == "furball":
        kwargs.update(given(inertia=table.vec3("inertia")))
        return furball(**kwargs, alpha=alpha, width=width)
    kwargs.update(
        given(
            radius=table.number("radius", lo=0, lo_open=True),
            coverage=table.number("coverage", lo=0, hi=1, lo_open=True),
        )
    )
    return scalp(**kwargs, alpha=alpha, width=width)


def _load_hair_file(table: Table, source: str, base_dir: Path, alpha: float, width: float) -> Strands:
    """Read a hair file (`HAIR_FILE_SUFFIXES`); a relative path is relative to the scene's
    directory."""
    path = Path(source)
    if not path.is_absolute():
        path = base_dir / path
    if path.is_dir():
        raise SceneError(f"{table.where}: hair.source {path}: is a directory, not a hair file")
    if not path.is_file():
        raise SceneError(
            f"{table.where}: hair.source file not found: {path} (from "
            f"{source!r}; relative paths are resolved against the scene "
            "file's directory)"
        )
    from .._io import load_hair  # at call time, so that tests can replace it

    try:
        return load_hair(path, alpha=alpha, width=width)
    except (OSError, ValueError) as e:  # ValueError includes HairFormatError.
        raise SceneError(f"{table.where}: hair.source could not be loaded: {e}") from e
