"""AMD TressFX hair (``.tfx``), versions 3.x and 4.x, little-endian.

The f32 at byte 0 is the version; both versions store S strands of the same vertex count V
and locate their arrays by absolute byte offsets in the header (0 = array absent).

TressFX 3.x, 296-byte header::

    0    f32  version (3.x)
    4    u32  strand count S
    8    u32  vertices per strand V
    12   u32  follow hairs per guide       (simulation only; ignored)
    16   u32  both-ends-immovable flag     (simulation only; ignored)
    20   124  reserved
    144  6 x u32 offsets: vertices, strand thickness, strand texcoords,
                          vertex colours, guide strands, vertex texcoords
    168  128  reserved

TressFX 4.x, 160-byte header::

    0    f32  version (4.x)
    4    u32  strand count S
    8    u32  vertices per strand V
    12   5 x u32 offsets: positions, strand UVs, vertex UVs, strand thickness, vertex colours
    32   128  reserved

Array element sizes. TressFX 4 (from its header comments): positions 4 x f32 per vertex
(xyz, and w = 0 for an immovable vertex), strand UVs 2 x f32 per strand, vertex UVs
2 x f32 per vertex, strand thickness f32 per strand, vertex colours 4 x f32 (RGBA) per vertex.
TressFX 3 positions are 3 x f32 per vertex. Its loader reads only positions and strand
texcoords (2 x f32 per strand); for its other optional arrays we assume the TressFX 4 sizes
(thickness f32 per strand, colours 4 x f32 and texcoords 2 x f32 per vertex) and one u32
per strand for the guide-strand index. No file at hand carries them.

Optional arrays go to `attributes`: "strand_thickness", "strand_uv", "vertex_uv",
"vertex_color" (RGBA, as stored), "guide_strand" (3.x) and "immovable" (4.x, bool per point).
"""

from __future__ import annotations

import dataclasses
import math
import struct
from typing import NamedTuple

import numpy as np

from .._errors import HairFormatError
from .._values._strands import first_outside

__all__ = ["parse_tfx", "tfx_version"]

HEADER_SIZE_V3 = 296
HEADER_SIZE_V4 = 160

# (attribute name, dtype, components, per "strand" or "vertex"), in header offset order.
_ARRAYS_V3 = [
    ("positions", "<f4", 3, "vertex"),
    ("strand_thickness", "<f4", 1, "strand"),
    ("strand_uv", "<f4", 2, "strand"),
    ("vertex_color", "<f4", 4, "vertex"),
    ("guide_strand", "<u4", 1, "strand"),
    ("vertex_uv", "<f4", 2, "vertex"),
]
_ARRAYS_V4 = [
    ("positions", "<f4", 4, "vertex"),
    ("strand_uv", "<f4", 2, "strand"),
    ("vertex_uv", "<f4", 2, "vertex"),
    ("strand_thickness", "<f4", 1, "strand"),
    ("vertex_color", "<f4", 4, "vertex"),
]


def tfx_version(data: bytes) -> float | None:
    """The version a TressFX file's first 4 bytes declare (the f32 at byte 0, as a Python
    float), or None when it is not a version this reader parses (3.x, 4.x) or the data is
    shorter than 4 bytes."""
    if len(data) < 4:
        return None
    (version,) = struct.unpack_from("<f", data, 0)
    return version if math.isfinite(version) and 3.0 <= version < 5.0 else None


class _Layout(NamedTuple):
    """Where a TressFX version keeps its arrays: its header's size, its arrays in header
    offset order, and the byte at which their offsets start."""

    header_size: int
    arrays: list[tuple[str, str, int, str]]
    offsets_at: int


_LAYOUT_V3 = _Layout(HEADER_SIZE_V3, _ARRAYS_V3, 144)
_LAYOUT_V4 = _Layout(HEADER_SIZE_V4, _ARRAYS_V4, 12)


@dataclasses.dataclass(frozen=True)
class _Arrays:
    """A TressFX file's arrays, located and checked: S strands of V vertices each, and each
    present array's byte span (start, end)."""

    data: bytes
    layout: _Layout
    strands: int
    per_strand: int
    spans: dict[str, tuple[int, int]]

    def read(self, name: str) -> np.ndarray:
        """The array `name` as stored: `[count, components]`, or `[count]` for one component."""
        _, dtype, components, per = next(a for a in self.layout.arrays if a[0] == name)
        count = self.strands * self.per_strand if per == "vertex" else self.strands
        flat = np.frombuffer(self.data, dtype, count * components, self.spans[name][0])
        return flat.reshape(count, components) if components > 1 else flat


def parse_tfx(data: bytes, path) -> dict:
    """Parse the bytes of a TressFX 3.x or 4.x file.

    Returns a dict with `points` (float64 [P, 3]), `offsets` (int64 [S + 1]), `color` (None:
    TressFX colours are kept as the "vertex_color" attribute) and `attributes`.
    Raises `HairFormatError` naming the problem for any malformed input.
    """
    layout = _layout(data, path)
    n_strands, per_strand = _counts(data, layout, path)
    arrays = _Arrays(data, layout, n_strands, per_strand, _spans(data, layout, n_strands, per_strand, path))
    positions = arrays.read("positions")
    xyz = positions[:, :3]
    if not np.all(np.isfinite(xyz)):
        bad = int(np.flatnonzero(~np.all(np.isfinite(xyz), axis=1))[0])
        raise HairFormatError(path, f"vertex {bad} has a NaN or infinite coordinate")
    return {
        "points": xyz.astype(np.float64),
        "offsets": np.arange(n_strands + 1, dtype=np.int64) * per_strand,
        "color": None,
        "attributes": _attributes(arrays, positions, path),
    }


def _layout(data: bytes, path) -> _Layout:
    """The layout of the version at byte 0, once the file holds that version's header."""
    size = len(data)
    if size < 12:
        raise HairFormatError(path, f"file is {size} bytes, too short for a TressFX header")
    version = tfx_version(data)
    if version is None:
        (declared,) = struct.unpack_from("<f", data, 0)
        raise HairFormatError(
            path, f"unsupported TressFX version {declared!r} at byte 0 (expected 3.x or 4.x)"
        )
    layout = _LAYOUT_V3 if version < 4.0 else _LAYOUT_V4
    if size < layout.header_size:
        raise HairFormatError(
            path, f"file is {size} bytes, shorter than the {layout.header_size}-byte TressFX header"
        )
    return layout


def _counts(data: bytes, layout: _Layout, path) -> tuple[int, int]:
    """(S strands, V vertices per strand), both ≥ 1, and positions that could fit the file."""
    size = len(data)
    n_strands, per_strand = struct.unpack_from("<II", data, 4)
    if n_strands == 0:
        raise HairFormatError(path, "the header declares zero strands")
    if per_strand == 0:
        raise HairFormatError(path, "the header declares zero vertices per strand")
    position_bytes = n_strands * per_strand * layout.arrays[0][2] * 4  # Python ints: no overflow
    if position_bytes > size:
        # Counts no offset could make fit: say so plainly (a file merely cut short is reported
        # by `_spans`, which names the array).
        raise HairFormatError(
            path,
            f"the header declares {n_strands} strands x {per_strand} vertices, whose positions "
            f"alone need {position_bytes} bytes, more than the {size}-byte file holds",
        )
    return n_strands, per_strand


def _spans(data: bytes, layout: _Layout, n_strands: int, per_strand: int, path) -> dict[str, tuple[int, int]]:
    """Each present array's byte span (start, end), checked to lie inside the file, after
    the header and apart from the others, before anything is read: absurd counts and stray
    offsets fail here. The positions must be present."""
    size = len(data)
    array_offsets = struct.unpack_from(f"<{len(layout.arrays)}I", data, layout.offsets_at)
    spans = {}
    for (name, _, components, per), start in zip(layout.arrays, array_offsets, strict=True):
        if start == 0:
            continue
        count = n_strands * per_strand if per == "vertex" else n_strands
        end = start + count * components * 4
        if start < layout.header_size:
            raise HairFormatError(
                path, f"{name} offset {start} points into the {layout.header_size}-byte header"
            )
        if start >= size:
            raise HairFormatError(path, f"{name} offset {start} points outside the file ({size} bytes)")
        if end > size:
            raise HairFormatError(
                path,
                f"truncated {name} array: {count} {per}s need bytes {start}..{end}, but the file has {size}",
            )
        spans[name] = (start, end)
    if "positions" not in spans:
        raise HairFormatError(path, "the positions array is missing (its offset is 0)")
    ordered = sorted(spans.items(), key=lambda item: item[1])
    for (name_a, (_, end_a)), (name_b, (start_b, _)) in zip(ordered, ordered[1:]):
        if start_b < end_a:
            raise HairFormatError(path, f"arrays {name_a} and {name_b} overlap")
    return spans


def _attributes(arrays: _Arrays, positions: np.ndarray, path) -> dict:
    """The optional arrays by name (unsigned ones as int64, the others float64), and for
    TressFX 4 "immovable", in the ranges of docs/scenes.md "Input ranges"."""
    attributes = {}
    if positions.shape[1] == 4:
        # TressFX 4 stores the inverse-mass flag in w: 0 pins the vertex (roots).
        attributes["immovable"] = positions[:, 3] == 0
    for name in arrays.spans:
        if name != "positions":
            values = arrays.read(name)
            attributes[name] = values.astype(np.int64 if values.dtype.kind == "u" else np.float64)
    # Each rule's name, the value's, the range.
    for name, what, lo, lo_open in (
        ("strand_thickness", "thickness of strand", 0.0, True),
        ("vertex_color", "colour (RGBA) of vertex", 0.0, False),
    ):
        outside = None if name not in attributes else first_outside(attributes[name], lo=lo, lo_open=lo_open)
        if outside is not None:
            value = np.atleast_1d(attributes[name][outside])
            rule = "finite and > 0" if lo_open else "finite and ≥ 0"
            raise HairFormatError(
                path, f"the {what} {outside} is {', '.join(f'{v:g}' for v in value)}; it must be {rule}"
            )
    return attributes
