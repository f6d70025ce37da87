"""Reading and writing hair files as `Strands`, and summarising them for `hairjax info`.

One module per format, each a pure function of the file's bytes (USD: of its path):

- `_hair`: Cem Yuksel's HAIR (``.hair``);
- `_tfx`: AMD TressFX 3.x and 4.x (``.tfx``);
- `_ply`: PLY with a per-strand segment count (``.ply``), ASCII or binary little-endian;
- `_usc`: USC-HairSalon (``.data``), read and written;
- `_usd`: USD `BasisCurves` (``.usd``, ``.usda``, ``.usdc``, ``.usdz``) through the
  optional usd-core, read and written.

Every problem with a file's content raises `HairFormatError(path, problem)`, values out
of their documented ranges included (docs/scenes.md "Input ranges"); strands with fewer
than two distinct points are dropped with one warning.
"""

from __future__ import annotations

import struct
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

import numpy as np

from .._errors import HairFormatError
from .._values._strands import Strands, distinct_strands, select_strands
from ._files import atomic_path
from ._hair import parse_hair
from ._ply import parse_ply
from ._tfx import parse_tfx, tfx_version
from ._usc import data_bytes, parse_data
from ._usd import USD_SUFFIXES, read_usd, write_usd

__all__ = ["load_hair", "save_hair", "hair_info", "format_info", "file_format", "FORMATS"]


class HairFormat(NamedTuple):
    """A hair file format: its name for messages, its reader (path → the fields of
    `Strands`) and its writer (`Strands`, path → None), or None where it is read only."""

    name: str
    read: Callable[[Path], dict]
    write: Callable[[Strands, Path], None] | None = None


def _from_bytes(parse: Callable[[bytes, Path], dict]) -> Callable[[Path], dict]:
    """A reader of the file's bytes through `parse(data, path)`."""

    def read(path: Path) -> dict:
        try:
            data = path.read_bytes()
        except OSError as error:
            raise HairFormatError(path, f"cannot read the file: {error.strerror or error}") from error
        # Casting float32 to float64 raises the 'invalid' flag for signalling NaNs, which
        # numpy reports as a RuntimeWarning; the parsers and Strands check finiteness.
        with np.errstate(invalid="ignore"):
            return parse(data, path)

    return read


def _write_data(strands: Strands, path: Path) -> None:
    path.write_bytes(data_bytes(strands.points, strands.offsets))


def _write_usd(strands: Strands, path: Path) -> None:
    write_usd(path, strands.points, strands.offsets, strands.color, strands.attributes.get("widths"))


# Suffix (lower case) -> format.
FORMATS = {
    ".hair": HairFormat("Cem Yuksel HAIR", _from_bytes(parse_hair)),
    ".tfx": HairFormat("TressFX", _from_bytes(parse_tfx)),
    ".ply": HairFormat("PLY", _from_bytes(parse_ply)),
    ".data": HairFormat("USC-HairSalon", _from_bytes(parse_data), _write_data),
} | {suffix: HairFormat("USD BasisCurves", read_usd, _write_usd) for suffix in USD_SUFFIXES}


def _format(path: Path, writing: bool = False) -> HairFormat:
    """The format of `path` by its suffix; `HairFormatError` listing the known suffixes
    (with `writing`, those hairjax writes) when it has none."""
    suffix = path.suffix.lower()
    if suffix not in FORMATS:
        raise HairFormatError(path, f"unknown file type {path.suffix!r} (known: {', '.join(FORMATS)})")
    if writing and FORMATS[suffix].write is None:
        writable = ", ".join(s for s, f in FORMATS.items() if f.write is not None)
        raise HairFormatError(
            path, f"hairjax reads {FORMATS[suffix].name} files but does not write them (writes: {writable})"
        )
    return FORMATS[suffix]


def load_hair(path, alpha=1.0, width=1.0) -> Strands:
    """Read a hair file into `Strands`, its format chosen by suffix (any case): `.hair`,
    `.tfx`, `.ply`, `.data` (USC-HairSalon), `.usd`/`.usda`/`.usdc`/`.usdz` (USD
    `BasisCurves`, with the optional usd-core).

    `alpha` and `width` (scalars or one value per strand of the file) are not stored in
    these formats and are passed to `Strands`. Per-point colour becomes `Strands.color`; the
    other arrays a file carries go to `Strands.attributes`. Strands with fewer than two
    distinct points (one point, or all points the same) are dropped, with one
    `UserWarning` that counts them.

    Raises `HairFormatError` naming the file and the problem when the suffix is unknown, the
    file cannot be read, its content is malformed or out of range (docs/scenes.md "Input
    ranges"), or no strand is left; `MissingDependency` for USD without usd-core.
    """
    path = Path(path)
    read = _format(path).read
    if path.is_dir():
        raise HairFormatError(path, "is a directory, not a hair file")
    try:
        fields = read(path)
    except HairFormatError:
        raise
    except (ValueError, IndexError, struct.error, OverflowError, MemoryError) as error:
        # The parsers check sizes and values before reading; this is a safety net so that a
        # case they missed still reports the file rather than a low-level error.
        raise HairFormatError(path, f"malformed file ({type(error).__name__}: {error})") from error
    try:
        strands = Strands(alpha=1.0, width=1.0, **fields)
    except ValueError as error:  # a value out of its range: the message names the point
        raise HairFormatError(path, str(error)) from error
    n = strands.num_strands
    # Outside the net: a bad alpha or width is the caller's error, a plain ValueError.
    alpha = np.broadcast_to(np.asarray(alpha, dtype=np.float64), (n,))
    width = np.broadcast_to(np.asarray(width, dtype=np.float64), (n,))
    keep = distinct_strands(strands)
    if not keep.any():
        raise HairFormatError(
            path, f"none of its {n} strands has two distinct points (one point, or all points the same)"
        )
    if not keep.all():
        warnings.warn(
            f"{path}: dropped {n - int(keep.sum())} of {n} strands with fewer than two distinct points",
            stacklevel=2,
        )
        strands = select_strands(strands, keep)
    return strands.replace(alpha=alpha[keep], width=width[keep])


def save_hair(strands: Strands, path) -> Path:
    """Write `strands` to a hair file, its format chosen by suffix (any case): `.data`
    (USC-HairSalon: points only) or `.usd`/`.usda`/`.usdc`/`.usdz` (USD `BasisCurves`:
    points, the per-point colour, and the "widths" attribute a USD file was read with;
    needs the optional usd-core). Points are written as float32. The file appears
    complete under its name, or not at all (it is written to a temporary file first).

    **Raises:** `HairFormatError` for a suffix no writer takes (the message lists those
    that are); `MissingDependency` for USD without usd-core; `OSError` when the file cannot
    be written.
    """
    path = Path(path)
    write = _format(path, writing=True).write
    assert write is not None  # _format checked it
    with atomic_path(path, path.suffix) as tmp:
        write(strands, Path(tmp))
    return path


def file_format(path) -> str:
    """The name of a hair file's format, by its suffix; for TressFX with the version its
    header declares (e.g. "TressFX 4.0"), read from the file's first 4 bytes."""
    path = Path(path)
    known = FORMATS.get(path.suffix.lower())
    name = "unknown format" if known is None else known.name
    if path.suffix.lower() != ".tfx":
        return name
    try:
        with open(path, "rb") as f:
            version = tfx_version(f.read(4))
    except OSError:  # fires for a file gone or unreadable since: the name alone
        return name
    if version is None:  # fires for a header no reader parses: load_hair says why
        return name
    # An f32 4.1 is 4.0999999: 6 significant digits give the number written, ".0" a round one.
    text = f"{version:.6g}"
    return f"{name} {text if '.' in text else text + '.0'}"


def hair_info(strands: Strands, path=None) -> dict:
    """A summary of `strands` as plain Python values.

    Keys: `strands`, `points`; `bbox_min`, `bbox_max` (3 floats each; None without points);
    `segment_length_min`, `segment_length_max` (over all segments; None without segments);
    `optional`: sorted names of the optional arrays present ("color" and the attributes);
    with the `path` the strands were read from, `format`: `file_format(path)` (for TressFX
    with its version, e.g. "TressFX 4.0").
    """
    points = strands.points
    bbox_min: list[float] | None
    bbox_max: list[float] | None
    seg_min: float | None
    seg_max: float | None
    if len(points):
        bbox_min = [float(v) for v in points.min(axis=0)]
        bbox_max = [float(v) for v in points.max(axis=0)]
    else:
        bbox_min = bbox_max = None
    segments = strands.segments()
    if len(segments):
        lengths = np.linalg.norm(points[segments[:, 1]] - points[segments[:, 0]], axis=1)
        seg_min, seg_max = float(lengths.min()), float(lengths.max())
    else:
        seg_min = seg_max = None
    optional = (["color"] if strands.color is not None else []) + list(strands.attributes)
    info: dict = {} if path is None else {"format": file_format(path)}
    return info | {
        "strands": strands.num_strands,
        "points": strands.num_points,
        "bbox_min": bbox_min,
        "bbox_max": bbox_max,
        "segment_length_min": seg_min,
        "segment_length_max": seg_max,
        "optional": sorted(optional),
    }


def format_info(path, info: dict) -> str:
    """Readable multi-line text of `hair_info` output, for `hairjax info FILE`; the format
    is `info["format"]`, or else `file_format(path)` (which reads a TressFX version)."""
    path = Path(path)
    kind = info.get("format") or file_format(path)

    def vec(v):
        return "-" if v is None else "(" + ", ".join(f"{x:.6g}" for x in v) + ")"

    if info["segment_length_min"] is None:
        seg = "- (no segments)"
    else:
        seg = f"{info['segment_length_min']:.6g} .. {info['segment_length_max']:.6g}"
    per_strand = info["points"] / info["strands"] if info["strands"] else 0.0
    rows = [
        ("format", kind),
        ("strands", f"{info['strands']:,}"),
        ("points", f"{info['points']:,} ({per_strand:.4g} per strand on average)"),
        ("bbox min", vec(info["bbox_min"])),
        ("bbox max", vec(info["bbox_max"])),
        ("segment length", seg),
        ("optional arrays", ", ".join(info["optional"]) or "none"),
    ]
    return "\n".join([str(path)] + [f"  {name:<16} {value}" for name, value in rows])
