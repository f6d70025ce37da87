"""Reading hair files into `Strands`, and summarising them for `hairjax info`.

One module per format, each a pure function of the file's bytes:

- `_hair`: Cem Yuksel's HAIR (``.hair``);
- `_tfx`: AMD TressFX 3.x and 4.x (``.tfx``);
- `_ply`: PLY with a per-strand segment count (``.ply``), ASCII or binary little-endian.

Every problem with a file's content raises `HairFormatError(path, problem)`.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

from .._errors import HairFormatError
from .._scene._strands import Strands
from ._hair import parse_hair
from ._ply import parse_ply
from ._tfx import parse_tfx, tfx_version

__all__ = ["load_hair", "hair_info", "format_info", "file_format", "FORMATS"]

# Suffix (lower case) -> (parser, name of the format for messages).
FORMATS = {
    ".hair": (parse_hair, "Cem Yuksel HAIR"),
    ".tfx": (parse_tfx, "TressFX"),
    ".ply": (parse_ply, "PLY"),
}


def load_hair(path, alpha=1.0, width=1.0) -> Strands:
    """Read a `.hair`, `.tfx` or `.ply` file into `Strands` (chosen by suffix, any case).

    `alpha` and `width` (scalars or one value per strand) are not stored in these formats
    and are passed to `Strands`. Per-point colour becomes `Strands.color`; the other arrays a
    file carries go to `Strands.attributes`.

    Raises `HairFormatError` naming the file and the problem when the suffix is unknown, the
    file cannot be read, or its content is malformed.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in FORMATS:
        known = ", ".join(FORMATS)
        raise HairFormatError(path, f"unknown hair file type {path.suffix!r} (known: {known})")
    parse, _ = FORMATS[suffix]
    if path.is_dir():
        raise HairFormatError(path, "is a directory, not a hair file")
    try:
        data = path.read_bytes()
    except OSError as error:
        raise HairFormatError(path, f"cannot read the file: {error.strerror or error}") from error
    try:
        # Casting float32 to float64 raises the 'invalid' flag for signalling NaNs, which
        # numpy reports as a RuntimeWarning; the parsers check finiteness where it matters.
        with np.errstate(invalid="ignore"):
            fields = parse(data, path)
    except HairFormatError:
        raise
    except (ValueError, IndexError, struct.error, OverflowError, MemoryError) as error:
        # The parsers check sizes and values before reading; this is a safety net so that a
        # case they missed still reports the file rather than a low-level error.
        raise HairFormatError(path, f"malformed file ({type(error).__name__}: {error})") from error
    # Outside the net: a bad alpha or width is the caller's error, a plain ValueError.
    return Strands(alpha=alpha, width=width, **fields)


def file_format(path) -> str:
    """The name of a hair file's format, by its suffix; for TressFX with the version its
    header declares (e.g. "TressFX 4.0"), read from the file's first 4 bytes."""
    path = Path(path)
    name = FORMATS.get(path.suffix.lower(), (None, "unknown format"))[1]
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
