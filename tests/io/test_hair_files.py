"""Hair file readers: real assets, hand-written round trips, malformed files, `hair_info`.

Files are written here byte by byte with `struct.pack`, independently of the readers, so a
reader and its test cannot share a misunderstanding of the layout.
"""

from __future__ import annotations

import math
import struct
from pathlib import Path

import numpy as np
import pytest
from helpers import DATA

from hairjax._errors import HairFormatError
from hairjax._io import format_info, hair_info, load_hair
from hairjax._values._strands import Strands

needs_data = pytest.mark.skipif(not DATA.is_dir(), reason=f"shared hair assets not found at {DATA}")

# From shared/data/README.md: file -> (strands, points).
REAL_FILES = {
    "tressfx/bear.tfx": (48_113, 192_452),
    "tressfx/TestHair1.tfx": (10_027, 40_108),
    "tressfx/ponytail_back.tfx": (517, 517 * 16),
    "tressfx/ponytail_front_top.tfx": (969, 969 * 16),
    "tressfx/ponytail_side.tfx": (3_066, 3_066 * 16),
    "tressfx/ponytail_tail.tfx": (255, 255 * 16),
    "tressfx/Ratboy_mohawk_v40.tfx": (2_226, 71_232),
    "tressfx/Ratboy_mohawk_v41.tfx": (2_228, 71_296),
    "tressfx/sintel_hair.tfx": (228, 7_296),
    "hair/Bangs_100.hair": (100, 1_165),
    "hair/Curly_100.ply": (100, 2_528),
}


# --------------------------------------------------------------------------- writers


def hair_bytes(
    strands,
    *,
    segments=True,
    default_segments=0,
    thickness=None,
    transparency=None,
    color=None,
    points=True,
    n_strands=None,
    n_points=None,
):
    """A HAIR file for `strands` (list of [n, 3] arrays); counts can be overridden."""
    flags = (1 if segments else 0) | (2 if points else 0)
    flags |= (4 if thickness is not None else 0) | (8 if transparency is not None else 0)
    flags |= 16 if color is not None else 0
    n_strands = len(strands) if n_strands is None else n_strands
    n_points = sum(len(s) for s in strands) if n_points is None else n_points
    header = struct.pack(
        "<4sIIIIff3f",
        b"HAIR",
        n_strands,
        n_points,
        flags,
        default_segments,
        1.0,
        0.0,
        1.0,
        1.0,
        1.0,
    )
    header += b"written by test_io".ljust(88, b"\0")
    assert len(header) == 128
    body = b""
    if segments:
        body += struct.pack(f"<{len(strands)}H", *[len(s) - 1 for s in strands])
    if points and strands:
        body += np.concatenate(strands).astype("<f4").tobytes()
    for array in (thickness, transparency, color):
        if array is not None:
            body += np.asarray(array, dtype="<f4").tobytes()
    return header + body


def tfx3_bytes(positions, *, arrays=None, version=3.0, n_strands=None, per_strand=None, offsets=None):
    """TressFX 3 file; `positions` is [S, V, 3]. `arrays` maps header slot -> bytes."""
    positions = np.asarray(positions, dtype="<f4")
    s, v = positions.shape[:2]
    blobs = {0: positions.tobytes(), **(arrays or {})}
    table, body, at = [0] * 6, b"", 296
    for slot in sorted(blobs):
        table[slot] = at
        body += blobs[slot]
        at += len(blobs[slot])
    table = offsets if offsets is not None else table
    header = struct.pack(
        "<fIIII",
        version,
        s if n_strands is None else n_strands,
        v if per_strand is None else per_strand,
        0,
        0,
    )
    header += bytes(124) + struct.pack("<6I", *table) + bytes(128)
    assert len(header) == 296
    return header + body


def tfx4_bytes(
    positions,
    *,
    arrays=None,
    version=4.0,
    n_strands=None,
    per_strand=None,
    offsets=None,
    order=None,
):
    """TressFX 4 file; `positions` is [S, V, 4]. Arrays are written in `order` of slots."""
    positions = np.asarray(positions, dtype="<f4")
    s, v = positions.shape[:2]
    blobs = {0: positions.tobytes(), **(arrays or {})}
    table, body, at = [0] * 5, b"", 160
    for slot in order or sorted(blobs):
        table[slot] = at
        body += blobs[slot]
        at += len(blobs[slot])
    table = offsets if offsets is not None else table
    header = struct.pack(
        "<fII5I",
        version,
        s if n_strands is None else n_strands,
        v if per_strand is None else per_strand,
        *table,
    ) + bytes(128)
    assert len(header) == 160
    return header + body


def ply_bytes(
    strands,
    *,
    fmt="binary_little_endian",
    color=None,
    color_type="uchar",
    edges=True,
    counts=None,
    header_extra="",
    body_extra=b"",
):
    """A hapPLY-style hair PLY: vertex x y z [rgb], strand nsegs, edge vertex1 vertex2."""
    pts = np.concatenate(strands).astype("<f4")
    nsegs = [len(s) - 1 for s in strands]
    pairs = [
        (o + i, o + i + 1)
        for o, s in zip(np.cumsum([0] + [len(s) for s in strands]), strands)
        for i in range(len(s) - 1)
    ]
    n_v, n_s, n_e = counts or (len(pts), len(strands), len(pairs))
    lines = [
        "ply",
        f"format {fmt} 1.0",
        "comment test",
        f"element vertex {n_v}",
        "property float x",
        "property float y",
        "property float z",
    ]
    if color is not None:
        lines += [f"property {color_type} {c}" for c in ("red", "green", "blue")]
    lines += [f"element strand {n_s}", "property ushort nsegs"]
    if edges:
        lines += [f"element edge {n_e}", "property int vertex1", "property int vertex2"]
    lines += [header_extra] if header_extra else []
    header = ("\n".join(lines) + "\nend_header\n").encode()
    if fmt == "ascii":
        rows = []
        for i, p in enumerate(pts):
            extra = [] if color is None else [str(c) for c in color[i]]
            rows.append(" ".join([repr(float(x)) for x in p] + extra))
        rows += [str(n) for n in nsegs]
        rows += [f"{a} {b}" for a, b in pairs] if edges else []
        return header + ("\n".join(rows) + "\n").encode() + body_extra
    ctype = {"uchar": "B", "float": "f", "double": "d"}[color_type]
    body = b""
    for i, p in enumerate(pts):
        body += struct.pack("<3f", *p)
        if color is not None:
            body += struct.pack(f"<3{ctype}", *color[i])
    body += struct.pack(f"<{len(nsegs)}H", *nsegs)
    if edges:
        body += b"".join(struct.pack("<ii", a, b) for a, b in pairs)
    return header + body + body_extra


def write(tmp_path, name, data) -> Path:
    path = tmp_path / name
    path.write_bytes(data)
    return path


# Ragged strands with values exact in float32: 3, 1 and 4 points.
RAGGED = [
    np.array([[0.0, 0.0, 0.0], [0.5, 1.0, -1.5], [1.0, 2.25, -3.0]]),
    np.array([[-4.0, 8.0, 16.0], [-4.0, 8.0, 17.0]]),
    np.array([[1.0, 1.0, 1.0], [1.0, 1.0, 2.0], [1.0, 2.0, 2.0]]),
]
RAGGED_OFFSETS = [0, 3, 5, 8]
RAGGED_POINTS = np.concatenate(RAGGED)


# --------------------------------------------------------------------------- (a) real files


@needs_data
def test_every_asset_is_listed():
    """A new asset in shared/data must be added to REAL_FILES (and so be checked)."""
    found = {str(p.relative_to(DATA)) for ext in ("tfx", "hair", "ply") for p in DATA.rglob(f"*.{ext}")}
    assert found == set(REAL_FILES)


@needs_data
@pytest.mark.parametrize("name", sorted(REAL_FILES))
def test_real_file_counts(name):
    strands = load_hair(DATA / name)
    n_strands, n_points = REAL_FILES[name]
    assert strands.num_strands == n_strands
    assert strands.num_points == n_points
    assert np.all(np.isfinite(strands.points))
    if name.endswith(".tfx"):  # TressFX: every strand has the same vertex count
        per = np.diff(strands.offsets)
        assert np.all(per == n_points // n_strands)


def _tfx_spans(data: bytes):
    """(header size, [(start, end)] of every present array), decoded here with struct."""
    (version,) = struct.unpack_from("<f", data, 0)
    s, v = struct.unpack_from("<II", data, 4)
    if version < 4:
        sizes = [12 * v, 4, 8, 16 * v, 4, 8 * v]  # bytes per strand for each slot
        table, header = struct.unpack_from("<6I", data, 144), 296
    else:
        sizes = [16 * v, 8, 8 * v, 4, 16 * v]
        table, header = struct.unpack_from("<5I", data, 12), 160
    return header, [(o, o + s * size) for o, size in zip(table, sizes) if o]


@needs_data
@pytest.mark.parametrize("name", sorted(n for n in REAL_FILES if n.endswith(".tfx")))
def test_tfx_bytes_accounted(name):
    """Header plus arrays tile the file exactly: no gap, no overlap, nothing past the end."""
    data = (DATA / name).read_bytes()
    header, spans = _tfx_spans(data)
    spans.sort()
    assert spans[0][0] == header
    for (_, end), (start, _) in zip(spans, spans[1:]):
        assert end == start
    assert spans[-1][1] == len(data)


@needs_data
def test_hair_bytes_accounted():
    data = (DATA / "hair/Bangs_100.hair").read_bytes()
    s, p, flags = struct.unpack_from("<III", data, 4)
    assert flags == 3  # segments and points only
    assert len(data) == 128 + 2 * s + 12 * p
    segments = np.frombuffer(data, "<u2", s, 128)
    assert 4 <= segments.min() and segments.max() <= 20  # README: 4-20 segments per strand
    strands = load_hair(DATA / "hair/Bangs_100.hair")
    assert np.array_equal(np.diff(strands.offsets), segments + 1)


@needs_data
def test_ply_bytes_accounted_and_colour():
    data = (DATA / "hair/Curly_100.ply").read_bytes()
    body = data.index(b"end_header\n") + len(b"end_header\n")
    # vertex: 3 float + 3 uchar; strand: ushort nsegs; edge: 2 int (header in the docstring).
    assert len(data) == body + 2528 * 15 + 100 * 2 + 2428 * 8
    strands = load_hair(DATA / "hair/Curly_100.ply")
    first = np.frombuffer(data, "<f4", 3, body)
    assert np.array_equal(strands.points[0], first.astype(np.float64))
    assert np.array_equal(strands.color[0] * 255, np.frombuffer(data, "u1", 3, body + 12))
    assert strands.color.min() >= 0 and strands.color.max() <= 1


@needs_data
def test_tfx4_immovable_roots():
    strands = load_hair(DATA / "tressfx/sintel_hair.tfx")
    immovable = strands.attributes["immovable"]
    assert immovable.dtype == bool and immovable.shape == (7296,)
    assert np.all(immovable[strands.offsets[:-1]])  # every root is pinned
    ratboy = load_hair(DATA / "tressfx/Ratboy_mohawk_v40.tfx")
    assert ratboy.attributes["strand_uv"].shape == (2226, 2)


# --------------------------------------------------------------------------- (b) round trips


def test_hair_round_trip_ragged(tmp_path):
    thickness = (np.arange(8) + 1) * 0.25
    transparency = np.linspace(0, 1, 8).astype(np.float32)
    color = np.arange(24).reshape(8, 3) / 32
    path = write(
        tmp_path,
        "ragged.hair",
        hair_bytes(RAGGED, thickness=thickness, transparency=transparency, color=color),
    )
    strands = load_hair(path, alpha=0.5, width=2.0)
    assert np.array_equal(strands.points, RAGGED_POINTS)
    assert strands.offsets.tolist() == RAGGED_OFFSETS
    assert np.array_equal(strands.color, color)
    assert np.array_equal(strands.attributes["thickness"], thickness)
    assert np.array_equal(strands.attributes["transparency"], transparency.astype(np.float64))
    assert strands.alpha.tolist() == [0.5] * 3 and strands.width.tolist() == [2.0] * 3


def test_hair_default_segments(tmp_path):
    strands_in = [np.arange(9, dtype=float).reshape(3, 3) + 10 * k for k in range(4)]
    path = write(
        tmp_path,
        "default.HAIR",  # suffix in any case
        hair_bytes(strands_in, segments=False, default_segments=2),
    )
    strands = load_hair(path)
    assert strands.offsets.tolist() == [0, 3, 6, 9, 12]
    assert np.array_equal(strands.points, np.concatenate(strands_in))
    assert strands.color is None and strands.attributes == {}


def test_signalling_nan_in_attributes(tmp_path):
    """NaN bits cast without a warning: in a ranged attribute (thickness) they are refused
    naming the point, in another (TressFX's strand UVs) they are data and kept."""
    data = hair_bytes(RAGGED, thickness=np.ones(8))
    thickness_at = 128 + 6 + 8 * 12
    with pytest.raises(HairFormatError, match=r"snan\.hair: the thickness of point 1 is nan"):
        load_hair(write(tmp_path, "snan.hair", _patch(data, thickness_at + 4, SNAN)))
    tfx = tfx4_bytes(TWO_BY_FOUR_W, arrays={1: SNAN * 4})
    strands = load_hair(write(tmp_path, "snan.tfx", tfx))
    assert np.isnan(strands.attributes["strand_uv"]).all()


def test_tfx3_round_trip(tmp_path):
    positions = np.arange(2 * 4 * 3, dtype=float).reshape(2, 4, 3) * 0.5
    thickness = np.array([0.25, 0.75], "<f4")
    strand_uv = np.array([[0.0, 0.5], [1.0, 0.25]], "<f4")
    colors = np.linspace(0, 1, 2 * 4 * 4).reshape(8, 4).astype("<f4")
    vertex_uv = np.arange(16).reshape(8, 2).astype("<f4")
    arrays = {
        1: thickness.tobytes(),
        2: strand_uv.tobytes(),
        3: colors.tobytes(),
        5: vertex_uv.tobytes(),
    }
    strands = load_hair(write(tmp_path, "three.tfx", tfx3_bytes(positions, arrays=arrays)))
    assert np.array_equal(strands.points, positions.reshape(8, 3))
    assert strands.offsets.tolist() == [0, 4, 8]
    assert np.array_equal(strands.attributes["strand_thickness"], thickness)
    assert np.array_equal(strands.attributes["strand_uv"], strand_uv)
    assert np.array_equal(strands.attributes["vertex_color"], colors)
    assert np.array_equal(strands.attributes["vertex_uv"], vertex_uv)
    assert strands.color is None


def test_tfx4_round_trip_arrays_out_of_order(tmp_path):
    positions = np.zeros((3, 2, 4))
    positions[..., :3] = np.arange(18).reshape(3, 2, 3) - 4.5
    positions[:, 0, 3] = 0.0  # pinned roots
    positions[:, 1, 3] = 1.0
    strand_uv = np.array([[0.5, 0.5], [0.25, 0.0], [1.0, 1.0]], "<f4")
    thickness = np.array([1.0, 2.0, 3.0], "<f4")
    colors = np.full((6, 4), 0.5, "<f4")
    arrays = {1: strand_uv.tobytes(), 3: thickness.tobytes(), 4: colors.tobytes()}
    # Positions last: the reader must follow the offsets, not assume an order.
    data = tfx4_bytes(positions, arrays=arrays, order=[4, 1, 3, 0], version=4.1)
    strands = load_hair(write(tmp_path, "four.tfx", data))
    assert np.array_equal(strands.points, positions[..., :3].reshape(6, 3))
    assert strands.offsets.tolist() == [0, 2, 4, 6]
    assert strands.attributes["immovable"].tolist() == [True, False] * 3
    assert np.array_equal(strands.attributes["strand_uv"], strand_uv)
    assert np.array_equal(strands.attributes["strand_thickness"], thickness)
    assert np.array_equal(strands.attributes["vertex_color"], colors)
    assert "vertex_uv" not in strands.attributes


def test_ply_binary_round_trip_uchar_colour(tmp_path):
    color = np.arange(24).reshape(8, 3) * 10
    strands = load_hair(write(tmp_path, "bin.ply", ply_bytes(RAGGED, color=color)))
    assert np.array_equal(strands.points, RAGGED_POINTS)
    assert strands.offsets.tolist() == RAGGED_OFFSETS
    assert np.array_equal(strands.color, color / 255)


def test_ply_binary_float_colour_no_edges(tmp_path):
    color = np.linspace(0, 1, 24).reshape(8, 3).astype(np.float32)
    data = ply_bytes(RAGGED, color=color, color_type="float", edges=False)
    strands = load_hair(write(tmp_path, "float.ply", data))
    assert np.array_equal(strands.color, color.astype(np.float64))
    assert strands.offsets.tolist() == RAGGED_OFFSETS


def test_ply_ascii_round_trip(tmp_path):
    color = np.arange(24).reshape(8, 3)
    strands = load_hair(write(tmp_path, "text.ply", ply_bytes(RAGGED, fmt="ascii", color=color)))
    assert np.array_equal(strands.points, RAGGED_POINTS)
    assert strands.offsets.tolist() == RAGGED_OFFSETS
    assert np.array_equal(strands.color, color / 255)
    plain = load_hair(write(tmp_path, "plain.ply", ply_bytes(RAGGED, fmt="ascii", edges=False)))
    assert plain.color is None and plain.offsets.tolist() == RAGGED_OFFSETS


# --------------------------------------------------------------------------- (c) malformed files


def _nan_strands():
    bad = [s.copy() for s in RAGGED]
    bad[2][1, 1] = math.nan
    return bad


def _inf_strands():
    bad = [s.copy() for s in RAGGED]
    bad[0][2, 0] = -math.inf
    return bad


TWO_BY_FOUR = np.arange(24, dtype=float).reshape(2, 4, 3)
TWO_BY_FOUR_W = np.concatenate([TWO_BY_FOUR, np.ones((2, 4, 1))], axis=2)


def _with(positions, where, value):
    positions = positions.copy()
    positions[where] = value
    return positions


SNAN = struct.pack("<I", 0x7F800001)  # a signalling NaN: casting it raises the 'invalid' flag


def _patch(data: bytes, at: int, new: bytes) -> bytes:
    return data[:at] + new + data[at + len(new) :]


GOOD_HAIR = hair_bytes(RAGGED)
GOOD_TFX3 = tfx3_bytes(TWO_BY_FOUR)
GOOD_TFX4 = tfx4_bytes(TWO_BY_FOUR_W)
GOOD_PLY = ply_bytes(RAGGED, color=np.zeros((8, 3), int))

# (test id, file name, bytes, fragment the message must contain)
MALFORMED = [
    # HAIR
    ("hair-magic", "a.hair", b"HAIX" + GOOD_HAIR[4:], "magic"),
    ("hair-empty", "a.hair", b"", "magic"),
    ("hair-short-header", "a.hair", GOOD_HAIR[:100], "shorter than the 128-byte"),
    ("hair-truncated-points", "a.hair", GOOD_HAIR[:-5], "truncated"),
    ("hair-truncated-segments", "a.hair", GOOD_HAIR[: 128 + 3], "truncated"),
    # The last strand claims 2 segments instead of 3: 7 points declared by segments, 8 stored.
    (
        "hair-point-count",
        "a.hair",
        GOOD_HAIR[:132] + struct.pack("<H", 3) + GOOD_HAIR[134:],
        "sum over strands",
    ),
    (
        "hair-default-segments",
        "a.hair",
        hair_bytes(RAGGED, segments=False, default_segments=2),
        "default segments",
    ),
    ("hair-nan", "a.hair", hair_bytes(_nan_strands()), "NaN or infinite"),
    ("hair-inf", "a.hair", hair_bytes(_inf_strands()), "NaN or infinite"),
    ("hair-snan", "a.hair", _patch(GOOD_HAIR, 128 + 6 + 12, SNAN), "NaN or infinite"),
    ("hair-nan-colour", "a.hair", hair_bytes(RAGGED, color=np.full((8, 3), np.nan)), "colour"),
    (
        "hair-absurd-counts",
        "a.hair",
        hair_bytes(RAGGED, n_strands=2**32 - 1, n_points=2**32 - 1),
        "need",
    ),
    ("hair-fewer-points-than-strands", "a.hair", hair_bytes(RAGGED, n_points=2), "smaller than"),
    ("hair-zero-strands", "a.hair", hair_bytes([], n_points=0), "zero strands"),
    ("hair-no-points", "a.hair", hair_bytes(RAGGED, points=False), "points array is missing"),
    (
        "hair-unknown-flags",
        "a.hair",
        GOOD_HAIR[:12] + struct.pack("<I", 3 | 64) + GOOD_HAIR[16:],
        "unknown array flags",
    ),
    ("hair-trailing-bytes", "a.hair", GOOD_HAIR + b"\0" * 12, "unexpected bytes"),
    # TressFX 3
    ("tfx3-version", "a.tfx", tfx3_bytes(TWO_BY_FOUR, version=2.0), "version"),
    ("tfx3-version-nan", "a.tfx", tfx3_bytes(TWO_BY_FOUR, version=math.nan), "version"),
    ("tfx3-too-short", "a.tfx", GOOD_TFX3[:8], "too short"),
    ("tfx3-short-header", "a.tfx", GOOD_TFX3[:200], "shorter than the 296-byte"),
    ("tfx3-truncated-positions", "a.tfx", GOOD_TFX3[:-1], "truncated positions"),
    (
        "tfx3-truncated-uv",
        "a.tfx",
        tfx3_bytes(TWO_BY_FOUR, arrays={2: bytes(12)}),
        "truncated strand_uv",
    ),
    (
        "tfx3-offset-outside",
        "a.tfx",
        tfx3_bytes(TWO_BY_FOUR, offsets=[10**6, 0, 0, 0, 0, 0]),
        "outside the file",
    ),
    (
        "tfx3-offset-in-header",
        "a.tfx",
        tfx3_bytes(TWO_BY_FOUR, offsets=[100, 0, 0, 0, 0, 0]),
        "into the 296-byte header",
    ),
    ("tfx3-overlap", "a.tfx", tfx3_bytes(TWO_BY_FOUR, offsets=[296, 296, 0, 0, 0, 0]), "overlap"),
    ("tfx3-nan", "a.tfx", tfx3_bytes(_with(TWO_BY_FOUR, (1, 2, 0), math.nan)), "NaN or infinite"),
    ("tfx3-inf", "a.tfx", tfx3_bytes(_with(TWO_BY_FOUR, (0, 0, 1), math.inf)), "NaN or infinite"),
    (
        "tfx3-absurd-counts",
        "a.tfx",
        tfx3_bytes(TWO_BY_FOUR, n_strands=2**32 - 1, per_strand=2**32 - 1),
        "more than the 392-byte file holds",
    ),
    ("tfx3-zero-strands", "a.tfx", tfx3_bytes(TWO_BY_FOUR, n_strands=0), "zero strands"),
    ("tfx3-zero-vertices", "a.tfx", tfx3_bytes(TWO_BY_FOUR, per_strand=0), "zero vertices"),
    (
        "tfx3-no-positions",
        "a.tfx",
        tfx3_bytes(TWO_BY_FOUR, offsets=[0] * 6),
        "positions array is missing",
    ),
    # TressFX 4
    ("tfx4-version", "a.tfx", tfx4_bytes(TWO_BY_FOUR_W, version=5.0), "version"),
    ("tfx4-version-garbage", "a.tfx", b"HAIR" + GOOD_TFX4[4:], "version"),
    ("tfx4-short-header", "a.tfx", GOOD_TFX4[:159], "shorter than the 160-byte"),
    ("tfx4-truncated-positions", "a.tfx", GOOD_TFX4[:-16], "truncated positions"),
    (
        "tfx4-truncated-colours",
        "a.tfx",
        tfx4_bytes(TWO_BY_FOUR_W, arrays={4: bytes(16 * 7)}),
        "truncated vertex_color",
    ),
    (
        "tfx4-offset-outside",
        "a.tfx",
        tfx4_bytes(TWO_BY_FOUR_W, offsets=[160, 2**32 - 8, 0, 0, 0]),
        "outside the file",
    ),
    (
        "tfx4-offset-in-header",
        "a.tfx",
        tfx4_bytes(TWO_BY_FOUR_W, offsets=[8, 0, 0, 0, 0]),
        "into the 160-byte header",
    ),
    ("tfx4-nan", "a.tfx", tfx4_bytes(_with(TWO_BY_FOUR_W, (0, 3, 2), math.nan)), "NaN or infinite"),
    ("tfx4-snan", "a.tfx", _patch(GOOD_TFX4, 160 + 16 + 4, SNAN), "NaN or infinite"),
    (
        "tfx4-absurd-counts",
        "a.tfx",
        tfx4_bytes(TWO_BY_FOUR_W, n_strands=10**9),
        "more than the 288-byte file holds",
    ),
    ("tfx4-zero-strands", "a.tfx", tfx4_bytes(TWO_BY_FOUR_W, n_strands=0), "zero strands"),
    ("tfx4-zero-vertices", "a.tfx", tfx4_bytes(TWO_BY_FOUR_W, per_strand=0), "zero vertices"),
    (
        "tfx4-no-positions",
        "a.tfx",
        tfx4_bytes(TWO_BY_FOUR_W, offsets=[0, 160, 0, 0, 0]),
        "positions array is missing",
    ),
    # PLY
    ("ply-magic", "a.ply", b"plx\n" + GOOD_PLY[4:], "not a PLY file"),
    ("ply-no-end-header", "a.ply", GOOD_PLY[:60], "end_header"),
    (
        "ply-no-format",
        "a.ply",
        GOOD_PLY.replace(b"format binary_little_endian 1.0\n", b""),
        "no 'format' line",
    ),
    ("ply-big-endian", "a.ply", ply_bytes(RAGGED, fmt="binary_big_endian"), "big-endian"),
    ("ply-truncated", "a.ply", GOOD_PLY[:-3], "truncated"),
    ("ply-trailing-bytes", "a.ply", GOOD_PLY + b"\0\0", "unexpected bytes"),
    (
        "ply-ascii-truncated",
        "a.ply",
        ply_bytes(RAGGED, fmt="ascii").rsplit(b"\n", 3)[0] + b"\n",
        "truncated",
    ),
    (
        "ply-ascii-not-a-number",
        "a.ply",
        ply_bytes(RAGGED, fmt="ascii").replace(b"0.5", b"0.5x"),
        "not a number",
    ),
    ("ply-ascii-nan", "a.ply", ply_bytes(_nan_strands(), fmt="ascii"), "NaN or infinite"),
    ("ply-nan", "a.ply", ply_bytes(_nan_strands()), "NaN or infinite"),
    (
        "ply-snan",
        "a.ply",
        _patch(GOOD_PLY, GOOD_PLY.index(b"end_header\n") + 11 + 15, SNAN),
        "NaN or infinite",
    ),
    ("ply-inf", "a.ply", ply_bytes(_inf_strands()), "NaN or infinite"),
    # The last strand's nsegs (the file's last two bytes without edges) says 2 instead of 3.
    (
        "ply-point-count",
        "a.ply",
        ply_bytes(RAGGED, edges=False)[:-2] + struct.pack("<H", 3),
        "nsegs",
    ),
    ("ply-absurd-counts", "a.ply", ply_bytes(RAGGED, counts=(4_000_000_000, 3, 5)), "need"),
    (
        "ply-ascii-absurd-counts",
        "a.ply",
        ply_bytes(RAGGED, fmt="ascii", counts=(10**12, 3, 5)),
        "truncated",
    ),
    (
        "ply-absurd-digits",
        "a.ply",
        GOOD_PLY.replace(b"vertex 8", b"vertex " + b"9" * 5000),
        "absurd row count",
    ),
    (
        "ply-zero-strands",
        "a.ply",
        b"ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\n"
        b"property float y\nproperty float z\nelement strand 0\nproperty ushort nsegs\n"
        b"end_header\n",
        "zero strands",
    ),
    (
        "ply-no-strand-element",
        "a.ply",
        b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
        b"property float z\nend_header\n0 0 0\n1 1 1\n",
        "cannot delimit strands",
    ),
    (
        "ply-missing-z",
        "a.ply",
        b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
        b"element strand 1\nproperty ushort nsegs\nend_header\n0 0\n1 1\n1\n",
        "lacks property z",
    ),
    (
        "ply-list-property",
        "a.ply",
        ply_bytes(RAGGED, header_extra="element face 0\nproperty list uchar int vertex_indices"),
        "list",
    ),
    (
        "ply-partial-colour",
        "a.ply",
        GOOD_PLY.replace(b"property uchar blue", b"property uchar alpha"),
        "incomplete",
    ),
    # One edge where the segment counts imply five.
    (
        "ply-edge-count",
        "a.ply",
        ply_bytes(RAGGED, edges=False).replace(
            b"end_header", b"element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header"
        )
        + struct.pack("<ii", 0, 1),
        "1 edges, but",
    ),
    ("ply-wrong-edge", "a.ply", ply_bytes(RAGGED)[:-8] + struct.pack("<ii", 5, 7), "edge 4 joins"),
]


@pytest.mark.parametrize("case", MALFORMED, ids=[case[0] for case in MALFORMED])
def test_malformed(tmp_path, case):
    _, name, data, fragment = case
    path = write(tmp_path, f"{case[0]}-{name}", data)
    with pytest.raises(HairFormatError) as caught:
        load_hair(path)
    message = str(caught.value)
    assert path.name in message
    assert fragment in message, message
    assert caught.value.path == str(path)


def test_a_directory_is_not_a_hair_file(tmp_path):
    folder = tmp_path / "adir.hair"
    folder.mkdir()
    with pytest.raises(HairFormatError, match=rf"^{folder}: is a directory, not a hair file$"):
        load_hair(folder)


def test_unknown_suffix_and_missing_file(tmp_path):
    path = write(tmp_path, "hair.obj", b"v 0 0 0\n")
    known = r"\(known: \.hair, \.tfx, \.ply, \.data, \.usd, \.usda, \.usdc, \.usdz\)"
    with pytest.raises(HairFormatError, match=rf"hair\.obj: unknown file type '\.obj' {known}$"):
        load_hair(path)
    with pytest.raises(HairFormatError, match=r"missing\.hair.*cannot read"):
        load_hair(tmp_path / "missing.hair")


@pytest.mark.parametrize(
    "name, data",
    [
        ("prefix.hair", hair_bytes(RAGGED, thickness=np.ones(8), color=np.ones((8, 3)))),
        ("prefix3.tfx", tfx3_bytes(TWO_BY_FOUR, arrays={2: bytes(16)})),
        ("prefix4.tfx", tfx4_bytes(TWO_BY_FOUR_W, arrays={1: bytes(16)})),
        ("prefix.ply", GOOD_PLY),
    ],
    ids=["hair", "tfx3", "tfx4", "ply"],
)
def test_every_truncation_is_reported(tmp_path, name, data):
    """Each format accounts for every byte, so every proper prefix must be rejected cleanly."""
    path = tmp_path / name
    for length in range(len(data)):
        path.write_bytes(data[:length])
        with pytest.raises(HairFormatError):
            load_hair(path)


@pytest.mark.parametrize(
    "name, data",
    [
        ("fuzz.hair", hair_bytes(RAGGED, transparency=np.ones(8))),
        ("fuzz3.tfx", GOOD_TFX3),
        ("fuzz4.tfx", tfx4_bytes(TWO_BY_FOUR_W, arrays={1: bytes(16), 3: bytes(8)})),
        ("fuzz.ply", GOOD_PLY),
        ("fuzz-ascii.ply", ply_bytes(RAGGED, fmt="ascii", color=np.ones((8, 3), int))),
    ],
    ids=["hair", "tfx3", "tfx4", "ply", "ply-ascii"],
)
def test_corrupted_bytes_never_escape(tmp_path, name, data):
    """Random byte corruption either still parses or raises HairFormatError, nothing else."""
    rng = np.random.default_rng(1234)
    path = tmp_path / name
    for _ in range(300):
        corrupted = bytearray(data)
        for at in rng.integers(0, len(data), size=rng.integers(1, 4)):
            corrupted[at] = int(rng.integers(0, 256))
        path.write_bytes(bytes(corrupted))
        try:
            strands = load_hair(path)
        except HairFormatError as error:
            assert name in str(error)
        else:
            assert isinstance(strands, Strands) and np.all(np.isfinite(strands.points))


# --------------------------------------------------------------------------- (d) hair_info


def test_hair_info_by_hand():
    strands = Strands.from_list(
        [
            [[0, 0, 0], [3, 4, 0], [3, 4, 12]],  # segments 5 and 12
            [[-1, 2, -3]],  # a single point: no segment
            [[1, 1, 1], [1, 1, 2]],  # segment 1
        ]
    )
    info = hair_info(strands)
    assert info["strands"] == 3 and info["points"] == 6
    assert info["bbox_min"] == [-1.0, 0.0, -3.0]
    assert info["bbox_max"] == [3.0, 4.0, 12.0]
    assert info["segment_length_min"] == 1.0
    assert info["segment_length_max"] == 12.0
    assert info["optional"] == []
    text = format_info("x.hair", info)
    assert "x.hair" in text and "HAIR" in text and "12" in text and "none" in text


def test_hair_info_optional_and_no_segments():
    strands = Strands(
        points=[[0.0, 0.0, 0.0], [2.0, -1.0, 5.0]],
        offsets=[0, 1, 2],
        alpha=1.0,
        width=1.0,
        color=[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        attributes={"transparency": np.zeros(2), "strand_uv": np.zeros((2, 2))},
    )
    info = hair_info(strands)
    assert info["optional"] == ["color", "strand_uv", "transparency"]
    assert info["segment_length_min"] is None and info["segment_length_max"] is None
    assert info["bbox_min"] == [0.0, -1.0, 0.0] and info["bbox_max"] == [2.0, 0.0, 5.0]
    text = format_info("two.ply", info)
    assert "no segments" in text and "color, strand_uv, transparency" in text


@needs_data
def test_hair_info_on_real_file():
    info = hair_info(load_hair(DATA / "tressfx/bear.tfx"))
    assert info["strands"] == 48_113 and info["points"] == 192_452
    # README: bear.tfx has segments as short as 2e-5.
    assert 0 < info["segment_length_min"] < 1e-4 < info["segment_length_max"]


@needs_data
@pytest.mark.parametrize(
    "name, version",
    [
        # Both Ratboy files declare 4.0 at byte 0 (bytes 00 00 80 40), the "v41" one too:
        # TressFX 4.1 kept the 4.0 file format.
        ("Ratboy_mohawk_v40.tfx", "4.0"),
        ("Ratboy_mohawk_v41.tfx", "4.0"),
        ("ponytail_tail.tfx", "3.0"),  # bytes 00 00 40 40
    ],
)
def test_info_shows_the_tressfx_version(name, version):
    path = DATA / "tressfx" / name
    strands = load_hair(path)
    assert hair_info(strands, path)["format"] == f"TressFX {version}"
    # `hairjax info` passes no path to hair_info: format_info reads the version itself.
    assert f"format           TressFX {version}\n" in format_info(path, hair_info(strands))


@pytest.mark.parametrize("version, text", [(4.1, "4.1"), (4.0, "4.0"), (3.5, "3.5"), (4.25, "4.25")])
def test_tressfx_version_as_written(tmp_path, version, text):
    path = tmp_path / "v.tfx"
    strand = np.arange(8.0).reshape(1, 2, 4)  # two distinct points
    path.write_bytes(tfx4_bytes(strand) if version >= 4 else tfx3_bytes(strand[..., :3]))
    data = bytearray(path.read_bytes())
    data[:4] = struct.pack("<f", version)
    path.write_bytes(bytes(data))
    assert hair_info(load_hair(path), path)["format"] == f"TressFX {text}"


def test_info_of_other_formats_names_them_without_version(tmp_path):
    strands = Strands.from_list([[[0, 0, 0], [1, 0, 0]]])
    assert hair_info(strands, "x.hair")["format"] == "Cem Yuksel HAIR"
    assert "format" not in hair_info(strands)
    assert "  format           PLY\n" in format_info("x.ply", hair_info(strands))
    # A .tfx path that cannot be read (gone since it was loaded) is named without version.
    assert hair_info(strands, tmp_path / "gone.tfx")["format"] == "TressFX"
