"""Cem Yuksel's HAIR format (``.hair``), little-endian.

Layout::

    offset  size  field
    0       4     magic b"HAIR"
    4       4     u32 strand count S
    8       4     u32 total point count P
    12      4     u32 bit field of the arrays present:
                    1 segments, 2 points, 4 thickness, 8 transparency, 16 colour
    16      4     u32 default segments per strand (used when there is no segments array)
    20      4     f32 default thickness
    24      4     f32 default transparency
    28      12    3 x f32 default colour
    40      88    free text, NUL-padded
    128     ...   the arrays whose bit is set, in this order, back to back:
                    segments      u16 per strand
                    points        3 x f32 per point
                    thickness     f32 per point
                    transparency  f32 per point
                    colour        3 x f32 per point

A strand with s segments has s + 1 points, so P = sum(s + 1). A file without the
points array has no geometry and is rejected. The defaults are not turned into arrays:
only what the file stores goes into the result.
"""

from __future__ import annotations

import struct
from typing import NamedTuple

import numpy as np

from .._errors import HairFormatError
from .._values._strands import first_outside

__all__ = ["parse_hair"]

HEADER_SIZE = 128
_HEADER = struct.Struct("<4sIII")  # magic, strands, points, flags (default values follow)

_SEGMENTS, _POINTS, _THICKNESS, _TRANSPARENCY, _COLOR = 1, 2, 4, 8, 16
_KNOWN_BITS = _SEGMENTS | _POINTS | _THICKNESS | _TRANSPARENCY | _COLOR


class _Header(NamedTuple):
    """The counts and array flags of a HAIR header."""

    strands: int
    points: int
    flags: int
    default_segments: int


def parse_hair(data: bytes, path) -> dict:
    """Parse the bytes of a HAIR file.

    Returns a dict with `points` (float64 [P, 3]), `offsets` (int64 [S + 1]), `color`
    (float64 [P, 3] or None) and `attributes` ("thickness", "transparency": float64 [P]).
    Raises `HairFormatError` naming the problem for any malformed input.
    """
    header = _read_header(data, path)
    layout = _layout(header, len(data), path)
    offsets = _strand_offsets(data, header, layout, path)
    points = _read_points(data, header, layout, path)
    attributes = _read_attributes(data, header, layout, path)
    color = None
    if "colour" in layout:
        color = np.frombuffer(data, "<f4", 3 * header.points, layout["colour"]).reshape(header.points, 3)
        color = color.astype(np.float64)  # its range is checked by Strands, naming the point
    return {"points": points.astype(np.float64), "offsets": offsets, "color": color, "attributes": attributes}


def _read_header(data: bytes, path) -> _Header:
    """The header's counts and flags, checked: the magic, a whole header, at least one
    strand and one point per strand, a points array and no unknown array."""
    size = len(data)
    if size < 4 or data[:4] != b"HAIR":
        raise HairFormatError(path, f"not a HAIR file: magic is {bytes(data[:4])!r}, expected b'HAIR'")
    if size < HEADER_SIZE:
        raise HairFormatError(path, f"file is {size} bytes, shorter than the {HEADER_SIZE}-byte HAIR header")
    _, n_strands, n_points, flags = _HEADER.unpack_from(data, 0)
    (default_segments,) = struct.unpack_from("<I", data, 16)
    if n_strands == 0:
        raise HairFormatError(path, "the header declares zero strands")
    if not flags & _POINTS:
        raise HairFormatError(path, "the points array is missing (bit 2 of the array flags is unset)")
    if flags & ~_KNOWN_BITS:
        # Unknown bits would mean arrays of unknown size: the rest could not be located.
        raise HairFormatError(path, f"unknown array flags 0x{flags & ~_KNOWN_BITS:x} in the header")
    if n_points < n_strands:
        raise HairFormatError(path, f"point count {n_points} is smaller than the strand count {n_strands}")
    return _Header(n_strands, n_points, flags, default_segments)


def _layout(header: _Header, size: int, path) -> dict[str, int]:
    """Each present array's byte offset, after checking that together they fill the file
    exactly. Every byte the header asks for is computed with Python ints (no overflow) and
    compared with the file size before anything is allocated: absurd counts fail here."""
    arrays = [  # (flag, name, bytes per item, items)
        (_SEGMENTS, "segments", 2, header.strands),
        (_POINTS, "points", 12, header.points),
        (_THICKNESS, "thickness", 4, header.points),
        (_TRANSPARENCY, "transparency", 4, header.points),
        (_COLOR, "colour", 12, header.points),
    ]
    layout = {}
    offset = HEADER_SIZE
    for flag, name, item_size, count in arrays:
        if header.flags & flag:
            layout[name] = offset
            offset += item_size * count
    if offset > size:
        raise HairFormatError(
            path,
            f"truncated: the header declares {header.strands} strands and {header.points} points, "
            f"which need {offset} bytes, but the file has {size} (cut short, or wrong counts)",
        )
    if offset < size:
        # The arrays are back to back with no padding; extra bytes mean the counts are wrong.
        raise HairFormatError(
            path, f"{size - offset} unexpected bytes after the last array (counts do not match the data)"
        )
    return layout


def _strand_offsets(data: bytes, header: _Header, layout: dict[str, int], path) -> np.ndarray:
    """`int64[S + 1]`: where each strand's points start, from the segments array or the
    default segment count; the points per strand must add up to the header's count."""
    n_strands, n_points = header.strands, header.points
    if "segments" in layout:
        segments = np.frombuffer(data, "<u2", n_strands, layout["segments"]).astype(np.int64)
    else:
        if n_points != n_strands * (header.default_segments + 1):
            raise HairFormatError(
                path,
                f"point count {n_points} != {n_strands} strands x "
                f"({header.default_segments} default segments + 1)",
            )
        segments = np.full(n_strands, header.default_segments, dtype=np.int64)
    counts = segments + 1
    if int(counts.sum()) != n_points:
        raise HairFormatError(
            path, f"point count {n_points} != sum over strands of (segments + 1) = {int(counts.sum())}"
        )
    offsets = np.zeros(n_strands + 1, dtype=np.int64)
    np.cumsum(counts, out=offsets[1:])
    return offsets


def _read_points(data: bytes, header: _Header, layout: dict[str, int], path) -> np.ndarray:
    """`float32[P, 3]`: the points, each coordinate finite."""
    points = np.frombuffer(data, "<f4", 3 * header.points, layout["points"]).reshape(header.points, 3)
    if not np.all(np.isfinite(points)):
        bad = int(np.flatnonzero(~np.all(np.isfinite(points), axis=1))[0])
        raise HairFormatError(path, f"point {bad} has a NaN or infinite coordinate")
    return points


def _read_attributes(data: bytes, header: _Header, layout: dict[str, int], path) -> dict:
    """The stored per-point "thickness" and "transparency" (float64 [P]), in the ranges of
    docs/scenes.md "Input ranges": a thickness is a fibre diameter, a transparency a
    fraction of light let through."""
    attributes = {}
    for name in ("thickness", "transparency"):
        if name in layout:
            attributes[name] = np.frombuffer(data, "<f4", header.points, layout[name]).astype(np.float64)
    if "thickness" in attributes:
        outside = first_outside(attributes["thickness"], lo=0.0, lo_open=True)
        if outside is not None:
            value = attributes["thickness"][outside]
            raise HairFormatError(
                path, f"the thickness of point {outside} is {value:g}; it must be finite and > 0"
            )
    if "transparency" in attributes:
        outside = first_outside(attributes["transparency"], lo=0.0, hi=1.0)
        if outside is not None:
            value = attributes["transparency"][outside]
            raise HairFormatError(
                path, f"the transparency of point {outside} is {value:g}; it must lie in [0, 1]"
            )
    return attributes
