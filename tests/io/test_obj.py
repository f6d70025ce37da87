"""OBJ reader (hairjax/_io/_obj.py): hand-written files, malformed ones, the real head."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import DATA

from hairjax._errors import MeshFormatError
from hairjax._io._obj import load_obj


def write(tmp_path, text, name="m.obj"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_every_face_form_and_negative_indices(tmp_path):
    text = """# a comment
o thing
v 0 0 0
v 1 0 0
v 1 1 0 1.0
v 0 1 0
vt 0 0
vn 0 0 1
s off
usemtl skin
f 1 2 3
f 1/1 3/1 4/1
f 1//1 2//1 4//1
f 2/1/1 3/1/1 4/1/1
f -4 -3 -1
"""
    v, f = load_obj(write(tmp_path, text))
    np.testing.assert_array_equal(v, [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    assert v.dtype == np.float64 and f.dtype == np.int32
    np.testing.assert_array_equal(f, [[0, 1, 2], [0, 2, 3], [0, 1, 3], [1, 2, 3], [0, 1, 3]])


def test_polygons_are_fanned(tmp_path):
    text = "v 0 0 0\nv 1 0 0\nv 2 1 0\nv 1 2 0\nv 0 1 0\nf 1 2 3 4 5\n"
    _, f = load_obj(write(tmp_path, text))
    np.testing.assert_array_equal(f, [[0, 1, 2], [0, 2, 3], [0, 3, 4]])


@pytest.mark.parametrize(
    "text, line, message",
    [
        ("v 0 0\nf 1 1 1\n", 1, "'v' needs 3 coordinates"),
        ("v 0 0 x\n", 1, "must be numbers"),
        ("v 0 0 nan\n", 1, "must be finite"),
        ("v 0 0 0\nv 1 0 0\nf 1 2\n", 3, "at least 3 vertices"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", 4, "refers to vertex 4, but 3 vertices"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", 4, "refers to vertex -4"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", 4, "indices start at 1"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/a 2 3\n", 4, "is not an index"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/2/3/4 2 3\n", 4, "is not v, v/vt"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf a 2 3\n", 4, "is not an index"),
    ],
)
def test_malformed_lines_name_the_file_and_line(tmp_path, text, line, message):
    path = write(tmp_path, text)
    with pytest.raises(MeshFormatError, match=message) as info:
        load_obj(path)
    assert str(info.value).startswith(f"{path}:{line}: ")


def test_empty_and_missing_files(tmp_path):
    with pytest.raises(MeshFormatError, match="no vertices"):
        load_obj(write(tmp_path, "# nothing\n"))
    with pytest.raises(MeshFormatError, match="no faces"):
        load_obj(write(tmp_path, "v 0 0 0\n"))
    with pytest.raises(MeshFormatError, match="cannot read"):
        load_obj(tmp_path / "absent.obj")


@pytest.mark.skipif(not DATA.is_dir(), reason=f"shared data not found at {DATA}")
def test_the_sintel_head():
    """shared/data/README.md: 3,046 vertices, 5,952 faces (all triangles in the file). The
    reader's vertex normals (hairjax/_occluder.py) point the way of the file's own `vn`
    at the same corners: the winding is outward."""
    from hairjax._geometry._occluder import vertex_normals

    path = DATA / "tressfx" / "sintel_head.obj"
    v, f = load_obj(path)
    assert v.shape == (3046, 3) and f.shape == (5952, 3)
    lines = path.read_text().splitlines()
    vn = np.array([[float(x) for x in ln.split()[1:4]] for ln in lines if ln.startswith("vn ")])
    corners = np.array(
        [[[int(x) for x in w.split("//")] for w in ln.split()[1:]] for ln in lines if ln.startswith("f ")]
    )
    np.testing.assert_array_equal(corners[..., 0] - 1, f)
    cos = np.sum(vertex_normals(v, f)[f] * vn[corners[..., 1] - 1], axis=-1)
    assert np.median(cos) > 0.99 and np.percentile(cos, 1) > 0.8
