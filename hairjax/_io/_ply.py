"""Hair strands in PLY (``.ply``), ASCII or binary little-endian.

PLY is a header of text lines followed by the elements' rows, element after element::

    ply
    format binary_little_endian 1.0      (or: format ascii 1.0)
    comment ...
    element vertex 2528
    property float x                     (x, y, z required; any numeric type)
    property float y
    property float z
    property uchar red                   (optional colour: uchar -> /255, or float/double as is)
    property uchar green
    property uchar blue
    element strand 100
    property ushort nsegs                (segments per strand; the strand has nsegs + 1 vertices)
    element edge 2428                    (optional)
    property int vertex1
    property int vertex2
    end_header
    <rows>

This is the layout hapPLY writes for hair (kenshi84/hairutil, CT2Hair): strands are
delimited by the per-strand segment counts of the `strand` element, vertices being stored
strand after strand. The `edge` element repeats that information as index pairs; when it
is present we check it joins exactly the consecutive vertices of every strand. A file
without a `strand` element with `nsegs` cannot be split into strands and is rejected, as are
big-endian files and list properties (neither occurs in hair files we know of).

Vertex properties other than x, y, z and the colour go to `attributes` under their own
name; strand properties other than nsegs under "strand_<name>". Other elements are skipped.
"""

from __future__ import annotations

import numpy as np

from .._errors import HairFormatError

__all__ = ["parse_ply"]

# PLY type names (both spellings) -> little-endian numpy dtype.
_TYPES = {
    "char": "i1", "int8": "i1",
    "uchar": "u1", "uint8": "u1",
    "short": "<i2", "int16": "<i2",
    "ushort": "<u2", "uint16": "<u2",
    "int": "<i4", "int32": "<i4",
    "uint": "<u4", "uint32": "<u4",
    "float": "<f4", "float32": "<f4",
    "double": "<f8", "float64": "<f8",
}  # fmt: skip

_MAX_HEADER = 1 << 20  # a header longer than 1 MiB is not a hair file's


def parse_ply(data: bytes, path) -> dict:
    """Parse the bytes of a hair PLY file (see the module docstring for what is supported).

    Returns a dict with `points` (float64 [P, 3]), `offsets` (int64 [S + 1]), `color`
    (float64 [P, 3] or None) and `attributes`.
    Raises `HairFormatError` naming the problem for any malformed input.
    """

    def fail(problem: str):
        raise HairFormatError(path, problem)

    fmt, elements, body_start = _parse_header(data, fail)
    if fmt == "ascii":
        values = _read_ascii(data, body_start, elements, fail)
    else:
        values = _read_binary(data, body_start, elements, fail)
    return _strands_from(values, elements, fail)


def _parse_header(data: bytes, fail):
    """-> (format, [(element name, count, [(property name, dtype)])], byte offset of the body)."""
    if not (data.startswith(b"ply\n") or data.startswith(b"ply\r\n")):
        fail(f"not a PLY file: it starts with {bytes(data[:4])!r}, expected b'ply' and a newline")
    end = -1
    for marker in (b"\nend_header\n", b"\nend_header\r\n"):
        at = data.find(marker, 0, _MAX_HEADER)
        if at >= 0 and (end < 0 or at < end):
            end, body_start = at, at + len(marker)
    if end < 0:
        fail("no 'end_header' line: the file is shorter than its header, or not a PLY file")
    try:
        lines = data[:end].decode("ascii").splitlines()[1:]
    except UnicodeDecodeError:
        fail("the header contains non-ASCII bytes")

    fmt = None
    elements: list[tuple[str, int, list[tuple[str, np.dtype]]]] = []
    for number, line in enumerate(lines, start=2):
        words = line.split()
        if not words or words[0] in ("comment", "obj_info"):
            continue
        if words[0] == "format":
            if len(words) != 3 or words[2] != "1.0":
                fail(f"header line {number}: bad format line {line!r}")
            if words[1] == "binary_big_endian":
                fail("big-endian binary PLY is not supported (only ascii and binary_little_endian)")
            if words[1] not in ("ascii", "binary_little_endian"):
                fail(f"header line {number}: unknown PLY format {words[1]!r}")
            fmt = words[1]
        elif words[0] == "element":
            if len(words) != 3 or not words[2].isdigit():
                fail(f"header line {number}: bad element line {line!r}")
            if len(words[2]) > 15:  # 10**15 rows fit in no file; also keeps int() cheap
                fail(f"header line {number}: absurd row count for element {words[1]!r}")
            if any(name == words[1] for name, _, _ in elements):
                fail(f"header line {number}: element {words[1]!r} declared twice")
            elements.append((words[1], int(words[2]), []))
        elif words[0] == "property":
            if not elements:
                fail(f"header line {number}: property before any element")
            name, _, props = elements[-1]
            if len(words) >= 2 and words[1] == "list":
                fail(f"list property in element {name!r} is not supported")
            if len(words) != 3 or words[1] not in _TYPES:
                fail(f"header line {number}: bad property line {line!r}")
            if any(prop == words[2] for prop, _ in props):
                fail(f"header line {number}: property {words[2]!r} of {name!r} declared twice")
            props.append((words[2], np.dtype(_TYPES[words[1]])))
        else:
            fail(f"header line {number}: unknown keyword {words[0]!r}")
    if fmt is None:
        fail("the header has no 'format' line")
    for name, count, props in elements:
        if count > 0 and not props:
            fail(f"element {name!r} has rows but no properties")
    return fmt, elements, body_start


def _read_binary(data: bytes, start: int, elements, fail) -> dict:
    """Rows of every element as a numpy structured array, by element name."""
    # Sizes first, from Python ints: absurd counts and truncation fail before any read.
    offset = start
    layout = []
    for name, count, props in elements:
        row = np.dtype(props) if props else np.dtype([])
        layout.append((name, count, row, offset))
        offset += count * row.itemsize
    if offset > len(data):
        counts = ", ".join(f"{count} {name}" for name, count, _ in elements)
        fail(
            f"truncated: the header declares {counts}, which need {offset - start} bytes "
            f"of data, but only {len(data) - start} follow the header"
        )
    if offset < len(data):
        fail(f"{len(data) - offset} unexpected bytes after the last element (counts do not match)")
    return {
        name: np.frombuffer(data, row, count, at) if row.itemsize else np.zeros(count, row)
        for name, count, row, at in layout
    }


def _read_ascii(data: bytes, start: int, elements, fail) -> dict:
    """Rows of every element as a dict of float64 columns, by element name."""
    # Each value needs at least a digit and a separator (the last one no separator): reject
    # absurd counts before splitting the text.
    n_values = sum(count * len(props) for _, count, props in elements)
    needed = max(2 * n_values - 1, 0)
    if needed > len(data) - start:
        fail(
            f"truncated: the header's element counts need at least {needed} bytes of ASCII data, "
            f"but only {len(data) - start} follow the header"
        )
    try:
        text = data[start:].decode("ascii")
    except UnicodeDecodeError:
        fail("the ASCII data contains non-ASCII bytes")
    lines = [line.split() for line in text.splitlines()]
    lines = [words for words in lines if words]  # blank lines carry nothing
    values = {}
    at = 0
    for name, count, props in elements:
        rows = lines[at : at + count]
        if len(rows) < count:
            fail(f"truncated: element {name!r} declares {count} rows, the file has {len(rows)}")
        for i, words in enumerate(rows):
            if len(words) != len(props):
                fail(f"element {name!r} row {i}: {len(words)} values, expected {len(props)}")
        try:
            table = np.array(rows, dtype=np.float64).reshape(count, len(props))
        except ValueError:
            fail(f"element {name!r} contains a value that is not a number")
        columns = {}
        for j, (prop, dtype) in enumerate(props):
            column = table[:, j]
            if dtype.kind in "iu":
                info = np.iinfo(dtype)
                ok = np.isfinite(column) & (column == np.round(column))
                ok &= (column >= info.min) & (column <= info.max)
                if not np.all(ok):
                    fail(f"element {name!r} property {prop!r}: values must be {dtype.name} integers")
                column = column.astype(np.int64)
            columns[prop] = column
        values[name] = columns
        at += count
    if at != len(lines):
        fail(f"{len(lines) - at} unexpected lines after the last element (counts do not match)")
    return values


def _strands_from(values: dict, elements, fail) -> dict:
    """Interpret the vertex / strand / edge elements as strands."""
    props_of = {name: dict(props) for name, _, props in elements}
    if "vertex" not in props_of:
        fail("no 'vertex' element")
    vertex, vprops = values["vertex"], props_of["vertex"]
    missing = [axis for axis in "xyz" if axis not in vprops]
    if missing:
        noun = "property" if len(missing) == 1 else "properties"
        fail(f"the vertex element lacks {noun} {', '.join(missing)}")
    n_points = len(vertex["x"])
    points = np.stack([np.asarray(vertex[axis], dtype=np.float64) for axis in "xyz"], axis=1)
    if not np.all(np.isfinite(points)):
        bad = int(np.flatnonzero(~np.all(np.isfinite(points), axis=1))[0])
        fail(f"vertex {bad} has a NaN or infinite coordinate")

    color = None
    rgb = [channel for channel in ("red", "green", "blue") if channel in vprops]
    if rgb and len(rgb) != 3:
        fail(f"the vertex colour is incomplete: only {', '.join(rgb)} present")
    if rgb:
        kinds = {vprops[channel].kind for channel in rgb}
        sizes = {vprops[channel].itemsize for channel in rgb}
        color = np.stack([np.asarray(vertex[c], dtype=np.float64) for c in rgb], axis=1)
        if kinds == {"u"} and sizes == {1}:
            color /= 255.0
        elif kinds != {"f"}:
            fail("vertex colours must be uchar (0..255) or float; got another type")
        # Their range (finite, ≥ 0) is checked by Strands, which names the point.
    attributes = {
        prop: np.array(vertex[prop]) for prop in vprops if prop not in ("x", "y", "z", "red", "green", "blue")
    }

    if "strand" not in props_of or "nsegs" not in props_of["strand"]:
        fail(
            "cannot delimit strands: expected a 'strand' element with an 'nsegs' property "
            "(segments per strand); elements present: " + ", ".join(props_of)
        )
    strand, sprops = values["strand"], props_of["strand"]
    if sprops["nsegs"].kind not in "iu":
        fail("strand property 'nsegs' must be an integer type")
    segments = np.asarray(strand["nsegs"], dtype=np.int64)
    n_strands = len(segments)
    if n_strands == 0:
        fail("the file declares zero strands")
    if np.any(segments < 0):
        fail("a strand has a negative segment count")
    counts = segments + 1
    if int(counts.sum()) != n_points:
        fail(f"vertex count {n_points} != sum over strands of (nsegs + 1) = {int(counts.sum())}")
    offsets = np.zeros(n_strands + 1, dtype=np.int64)
    np.cumsum(counts, out=offsets[1:])
    for prop in sprops:
        if prop != "nsegs":
            key = prop if prop.startswith("strand_") else f"strand_{prop}"
            attributes[key] = np.array(strand[prop])

    if "edge" in props_of:
        _check_edges(values["edge"], props_of["edge"], offsets, fail)
    return {"points": points, "offsets": offsets, "color": color, "attributes": attributes}


def _check_edges(edge, eprops, offsets, fail):
    """The edges must be exactly the consecutive vertex pairs inside each strand, in order."""
    if "vertex1" not in eprops or "vertex2" not in eprops:
        fail("the edge element needs integer properties 'vertex1' and 'vertex2'")
    if eprops["vertex1"].kind not in "iu" or eprops["vertex2"].kind not in "iu":
        fail("edge properties 'vertex1' and 'vertex2' must be integers")
    is_last = np.zeros(int(offsets[-1]), dtype=bool)
    is_last[offsets[1:] - 1] = True
    first = np.flatnonzero(~is_last)
    v1 = np.asarray(edge["vertex1"], dtype=np.int64)
    v2 = np.asarray(edge["vertex2"], dtype=np.int64)
    if len(v1) != len(first):
        fail(f"{len(v1)} edges, but the strands' segment counts add up to {len(first)} segments")
    wrong = np.flatnonzero((v1 != first) | (v2 != first + 1))
    if wrong.size:
        k = int(wrong[0])
        fail(
            f"edge {k} joins vertices {int(v1[k])} and {int(v2[k])}, but the strands' segment "
            f"counts put segment {k} between {int(first[k])} and {int(first[k]) + 1}"
        )
