"""Hair and mesh input against the ranges of docs/scenes.md "Input ranges": colours,
thickness, transparency, coordinates within ±1e18 (hairjax/_constants.py), OBJ vertices,
and strands with fewer than two distinct points. Files are written byte by byte here
(`struct.pack`), independently of the readers."""

from __future__ import annotations

import math
import struct

import numpy as np
import pytest

from hairjax._constants import COORDINATE_BOUND
from hairjax._errors import HairFormatError, MeshFormatError
from hairjax._io import load_hair
from hairjax._io._obj import load_obj
from hairjax._values._strands import Strands, distinct_strands, select_strands

THREE = [
    np.array([[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 2.0, 0.5]]),
    np.array([[1.0, 0.0, 0.0], [1.0, 1.0, 0.0]]),
    np.array([[2.0, 0.0, 0.0], [2.0, 1.0, 0.0], [2.0, 2.0, 0.0]]),
]


def hair_file(path, strands, *, color=None, thickness=None, transparency=None):
    """Cem Yuksel's HAIR layout (hairjax/_io/_hair.py's docstring), written by hand."""
    flags = 1 | 2 | (4 if thickness is not None else 0) | (8 if transparency is not None else 0)
    flags |= 16 if color is not None else 0
    n_points = sum(len(s) for s in strands)
    header = struct.pack("<4sIIIIff3f", b"HAIR", len(strands), n_points, flags, 0, 1.0, 0.0, 1.0, 1.0, 1.0)
    body = struct.pack(f"<{len(strands)}H", *[len(s) - 1 for s in strands])
    body += np.concatenate(strands).astype("<f4").tobytes()
    for array in (thickness, transparency, color):
        if array is not None:
            body += np.asarray(array, "<f4").tobytes()
    path.write_bytes(header + bytes(88) + body)
    return path


def ply_file(path, strands, color):
    """An ASCII PLY with float vertex colours and a per-strand segment count."""
    points = np.concatenate(strands)
    lines = [
        "ply",
        "format ascii 1.0",
        f"element vertex {len(points)}",
        *[f"property float {p}" for p in ("x", "y", "z", "red", "green", "blue")],
        f"element strand {len(strands)}",
        "property int nsegs",
        "end_header",
        *[" ".join(f"{v:g}" for v in (*p, *c)) for p, c in zip(points, color)],
        *[str(len(s) - 1) for s in strands],
    ]
    path.write_text("\n".join(lines) + "\n")
    return path


def tfx4_file(path, positions, thickness):
    """TressFX 4 (hairjax/_io/_tfx.py's docstring): positions xyzw, then strand thickness."""
    s, v, _ = positions.shape
    header = struct.pack("<fII5I", 4.0, s, v, 160, 0, 0, 160 + 16 * s * v, 0) + bytes(128)
    body = np.asarray(positions, "<f4").tobytes() + np.asarray(thickness, "<f4").tobytes()
    path.write_bytes(header + body)
    return path


# --------------------------------------------------------------------------- colours


def test_negative_colour_in_a_hair_file_names_the_file_and_point(tmp_path):
    color = np.full((8, 3), 0.5)
    color[4] = [-2.0, 0.5, 0.5]
    path = hair_file(tmp_path / "neg.hair", THREE, color=color)
    with pytest.raises(HairFormatError) as error:
        load_hair(path)
    assert str(error.value) == (
        f"{path}: the colour of point 4 is (-2, 0.5, 0.5): colours are linear RGB, finite and ≥ 0"
    )


@pytest.mark.parametrize("value", [math.nan, math.inf, -1e-3])
def test_colour_out_of_range_in_a_ply_file(tmp_path, value):
    color = np.full((8, 3), 0.25)
    color[7, 2] = value
    path = ply_file(tmp_path / "c.ply", THREE, color)
    with pytest.raises(HairFormatError, match=r"c\.ply: .*point 7 .*finite and ≥ 0"):
        load_hair(path)


def test_colours_above_one_are_allowed(tmp_path):
    """docs/model.md §1: linear RGB; values above 1 brighten (docs/scenes.md's RGB rule)."""
    color = np.full((8, 3), 3.0)
    color[0] = 0.0
    strands = load_hair(hair_file(tmp_path / "bright.hair", THREE, color=color))
    assert np.array_equal(strands.color, color)


def test_python_built_strands_refuse_a_negative_colour():
    with pytest.raises(ValueError, match=r"colour of point 1 is \(0, -1, 0\)"):
        Strands([[0, 0, 0], [1, 0, 0]], [0, 2], 1.0, 1.0, color=[[0, 0, 0], [0, -1, 0]])


# --------------------------------------------------------------------------- thickness, transparency


@pytest.mark.parametrize("value", [0.0, -1.0, math.inf, math.nan])
def test_thickness_must_be_positive_and_finite(tmp_path, value):
    thickness = np.ones(8)
    thickness[5] = value
    path = hair_file(tmp_path / "t.hair", THREE, thickness=thickness)
    with pytest.raises(HairFormatError, match=rf"t\.hair: the thickness of point 5 is {value:g}; .*> 0"):
        load_hair(path)


@pytest.mark.parametrize("value", [-0.1, 1.5, math.nan])
def test_transparency_must_lie_in_zero_one(tmp_path, value):
    transparency = np.linspace(0, 1, 8)  # both ends allowed
    transparency[3] = value
    path = hair_file(tmp_path / "t.hair", THREE, transparency=transparency)
    with pytest.raises(HairFormatError, match=r"t\.hair: the transparency of point 3 .*\[0, 1\]"):
        load_hair(path)


def test_tressfx_thickness_must_be_positive(tmp_path):
    positions = np.ones((2, 3, 4))
    positions[..., 1] = np.arange(3)  # distinct points along y
    good = load_hair(tfx4_file(tmp_path / "ok.tfx", positions, [0.5, 1.0]))
    assert good.attributes["strand_thickness"].tolist() == [0.5, 1.0]
    with pytest.raises(HairFormatError, match=r"bad\.tfx: the thickness of strand 1 is -0\.5"):
        load_hair(tfx4_file(tmp_path / "bad.tfx", positions, [0.5, -0.5]))


# --------------------------------------------------------------------------- coordinates


@pytest.mark.parametrize("value", [2e18, -3e38])
def test_coordinates_beyond_the_bound_name_the_point(tmp_path, value):
    strands = [s.copy() for s in THREE]
    strands[2][1, 0] = value
    path = hair_file(tmp_path / "far.hair", strands)
    with pytest.raises(HairFormatError, match=r"far\.hair: point 6 = .* lies beyond ±1e\+18"):
        load_hair(path)


def test_coordinates_at_the_bound_are_read(tmp_path):
    strands = [s * COORDINATE_BOUND / 2 for s in THREE]  # |x| ≤ 2 × bound / 2
    loaded = load_hair(hair_file(tmp_path / "big.hair", strands))
    np.testing.assert_allclose(loaded.points, np.concatenate(strands), rtol=2**-24)  # float32 storage


def test_python_built_strands_refuse_far_coordinates():
    with pytest.raises(ValueError, match=r"point 1 = \(0, 0, -1e\+20\) lies beyond"):
        Strands([[0, 0, 0], [0, 0, -1e20]], [0, 2], 1.0, 1.0)
    with pytest.raises(ValueError, match=r"point 0 has a NaN or infinite coordinate"):
        Strands([[0, math.inf, 0], [0, 0, 1]], [0, 2], 1.0, 1.0)


@pytest.mark.parametrize("value", ["1e39", "-2e18"])
def test_obj_vertex_beyond_the_bound_names_the_line(tmp_path, value):
    path = tmp_path / "m.obj"
    path.write_text(f"v 0 0 0\nv 1 {value} 0\nv 0 1 0\nf 1 2 3\n")
    with pytest.raises(MeshFormatError, match=r"m\.obj:2: 'v' coordinates must lie within ±1e\+18"):
        load_obj(path)


def test_obj_vertex_at_the_bound_is_read(tmp_path):
    path = tmp_path / "m.obj"
    path.write_text("v 0 0 0\nv 1e18 0 0\nv 0 -1e18 0\nf 1 2 3\n")
    vertices, _ = load_obj(path)
    assert vertices[1, 0] == 1e18 and vertices[2, 1] == -1e18


# --------------------------------------------------------------------------- degenerate strands


def test_one_point_and_coincident_strands_are_dropped_with_one_warning(tmp_path):
    strands = [
        np.array([[5.0, 5.0, 5.0]]),  # one point
        THREE[0],
        np.array([[1.0, 2.0, 3.0]] * 4),  # four coincident points
        THREE[1],
    ]
    color = np.arange(30).reshape(10, 3) / 30
    thickness = np.arange(1, 11) / 10
    path = hair_file(tmp_path / "d.hair", strands, color=color, thickness=thickness)
    with pytest.warns(UserWarning) as record:
        loaded = load_hair(path, alpha=[0.1, 0.2, 0.3, 0.4], width=2.0)
    assert [str(w.message) for w in record] == [
        f"{path}: dropped 2 of 4 strands with fewer than two distinct points"
    ]
    kept = [1, 2, 3, 8, 9]  # points of strands 1 and 3
    assert loaded.offsets.tolist() == [0, 3, 5]
    assert np.array_equal(loaded.points, np.concatenate(strands)[kept])
    assert np.array_equal(loaded.color, color[kept].astype(np.float32))  # stored as f32
    assert np.array_equal(loaded.attributes["thickness"], thickness[kept].astype(np.float32))
    assert loaded.alpha.tolist() == [0.2, 0.4] and loaded.width.tolist() == [2.0, 2.0]


def test_a_file_with_no_drawable_strand_is_refused(tmp_path):
    strands = [np.array([[0.0, 0.0, 0.0]]), np.array([[1.0, 1.0, 1.0]] * 3)]
    path = hair_file(tmp_path / "none.hair", strands)
    with pytest.raises(HairFormatError) as error:
        load_hair(path)
    assert str(error.value) == (
        f"{path}: none of its 2 strands has two distinct points (one point, or all points the same)"
    )


def test_distinct_strands_by_hand():
    strands = Strands.from_list(
        [
            [[0, 0, 0]],
            [[0, 0, 0], [0, 0, 0], [0, 0, 1]],  # moves at its last segment
            [[1, 1, 1], [1, 1, 1]],
            [[1, 1, 1], [2, 1, 1]],  # its first point equals the previous strand's last
        ]
    )
    assert distinct_strands(strands).tolist() == [False, True, False, True]
    subset = select_strands(strands, [False, True, False, True])
    assert subset.offsets.tolist() == [0, 3, 5] and subset.points[3].tolist() == [1, 1, 1]
