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

import numpy as np

from .._errors import HairFormatError
from .._values._strands import first_outside

__all__ = ["parse_hair"]

HEADER_SIZE = 128
_HEADER = struct.Struct("<4sIII")  # magic, strands, points, flags (default values follow)

_SEGMENTS, _POINTS, _THICKNESS, _TRANSPARENCY, _COLOR = 1, 2, 4, 8, 16
_KNOWN_BITS = _SEGMENTS | _POINTS | _THICKNESS | _TRANSPARENCY | _COLOR


def parse_hair(data: bytes, path) -> dict:
    """Parse the bytes of a HAIR file.

    Returns a dict with `points` (float64 [P, 3]), `offsets` (int64 [S + 1]), `color`
    (float64 [P, 3] or None) and `attributes` ("thickness", "transparency": float64 [P]).
    Raises `HairFormatError` naming the problem for any malformed input.
    """

    def fail(problem: str):
        raise HairFormatError(path, problem)

    size = len(data)
    if size < 4 or data[:4] != b"HAIR":
        fail(f"not a HAIR file: magic is {bytes(data[:4])!r}, expected b'HAIR'")
    if size < HEADER_SIZE:
        fail(f"file is {size} bytes, shorter than the {HEADER_SIZE}-byte HAIR header")
    _, n_strands, n_points, flags = _HEADER.unpack_from(data, 0)
    (default_segments,) = struct.unpack_from("<I", data, 16)

    if n_strands == 0:
        fail("the header declares zero strands")
    if not flags & _POINTS:
        fail("the points array is missing (bit 2 of the array flags is unset)")
    if flags & ~_KNOWN_BITS:
        # Unknown bits would mean arrays of unknown size: the rest could not be located.
        fail(f"unknown array flags 0x{flags & ~_KNOWN_BITS:x} in the header")
    if n_points < n_strands:
        fail(f"point count {n_points} is smaller than the strand count {n_strands}")

    # Every byte the header asks for, computed with Python ints (no overflow) and compared
    # with the file size before anything is allocated: absurd counts fail here.
    arrays = [  # (flag, name, bytes per item, items)
        (_SEGMENTS, "segments", 2, n_strands),
        (_POINTS, "points", 12, n_points),
        (_THICKNESS, "thickness", 4, n_points),
        (_TRANSPARENCY, "transparency", 4, n_points),
        (_COLOR, "colour", 12, n_points),
    ]
    layout = {}
    offset = HEADER_SIZE
    for flag, name, item_size, count in arrays:
        if flags & flag:
            layout[name] = offset
            offset += item_size * count
    if offset > size:
        fail(
            f"truncated: the header declares {n_strands} strands and {n_points} points, "
            f"which need {offset} bytes, but the file has {size} (cut short, or wrong counts)"
        )
    if offset < size:
        # The arrays are back to back with no padding; extra bytes mean the counts are wrong.
        fail(f"{size - offset} unexpected bytes after the last array (counts do not match the data)")

    if flags & _SEGMENTS:
        segments = np.frombuffer(data, "<u2", n_strands, layout["segments"]).astype(np.int64)
    else:
        if n_points != n_strands * (default_segments + 1):
            fail(f"point count {n_points} != {n_strands} strands x ({default_segments} default segments + 1)")
        segments = np.full(n_strands, default_segments, dtype=np.int64)
    counts = segments + 1
    if int(counts.sum()) != n_points:
        fail(f"point count {n_points} != sum over strands of (segments + 1) = {int(counts.sum())}")
    offsets = np.zeros(n_strands + 1, dtype=np.int64)
    np.cumsum(counts, out=offsets[1:])

    points = np.frombuffer(data, "<f4", 3 * n_points, layout["points"]).reshape(n_points, 3)
    if not np.all(np.isfinite(points)):
        bad = int(np.flatnonzero(~np.all(np.isfinite(points), axis=1))[0])
        fail(f"point {bad} has a NaN or infinite coordinate")

    attributes = {}
    for name in ("thickness", "transparency"):
        if name in layout:
            attributes[name] = np.frombuffer(data, "<f4", n_points, layout[name]).astype(np.float64)
    # The ranges of docs/scenes.md "Input ranges": a thickness is a fibre diameter, a
    # transparency a fraction of light let through.
    if "thickness" in attributes:
        outside = first_outside(attributes["thickness"], lo=0.0, lo_open=True)
        if outside is not None:
            value = attributes["thickness"][outside]
            fail(f"the thickness of point {outside} is {value:g}; it must be finite and > 0")
    if "transparency" in attributes:
        outside = first_outside(attributes["transparency"], lo=0.0, hi=1.0)
        if outside is not None:
            value = attributes["transparency"][outside]
            fail(f"the transparency of point {outside} is {value:g}; it must lie in [0, 1]")
    color = None
    if "colour" in layout:
        color = np.frombuffer(data, "<f4", 3 * n_points, layout["colour"]).reshape(n_points, 3)
        color = color.astype(np.float64)  # its range is checked by Strands, naming the point

    return {
        "points": points.astype(np.float64),
        "offsets": offsets,
        "color": color,
        "attributes": attributes,
    }
