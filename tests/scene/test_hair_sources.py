"""The [hair] table takes every hair file format hairjax/_io reads (`FORMATS`): the new
USC-HairSalon and USD files are scene sources too, and the allowed list names them."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from hairjax._errors import SceneError
from hairjax._io import FORMATS
from hairjax._scene._file import load_scene
from hairjax._scene._hair_table import HAIR_FILE_SUFFIXES

POINTS = np.array([[0, 0, 0], [0, 1, 0], [0, 2, 1], [1, 0, 0], [1, 1, 0]], np.float32)


def test_suffixes_are_the_readers():
    assert HAIR_FILE_SUFFIXES == tuple(FORMATS)
    assert {".data", ".usd", ".usda", ".usdc", ".usdz"} <= set(HAIR_FILE_SUFFIXES)


def test_a_data_file_as_scene_source(tmp_path):
    body = struct.pack("<i", 2)
    for part in (POINTS[:3], POINTS[3:]):
        body += struct.pack("<i", len(part)) + part.tobytes()
    (tmp_path / "h.data").write_bytes(body)
    (tmp_path / "s.toml").write_text('[hair]\nsource = "h.data"\nscale = 2.0\n')
    scene = load_scene(tmp_path / "s.toml")
    assert scene.strands.offsets.tolist() == [0, 3, 5]
    assert np.array_equal(scene.strands.points, 2.0 * POINTS)


def test_a_usd_file_as_scene_source(tmp_path):
    UsdGeom = pytest.importorskip("pxr.UsdGeom")
    from pxr import Usd, Vt

    stage = Usd.Stage.CreateNew(str(tmp_path / "h.usda"))
    curves = UsdGeom.BasisCurves.Define(stage, "/hair")
    curves.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(POINTS))
    curves.CreateCurveVertexCountsAttr(Vt.IntArray([3, 2]))
    stage.GetRootLayer().Save()
    (tmp_path / "s.toml").write_text('[hair]\nsource = "h.usda"\n')
    assert load_scene(tmp_path / "s.toml").strands.offsets.tolist() == [0, 3, 5]


def test_an_unknown_source_suffix_lists_the_formats(tmp_path):
    (tmp_path / "s.toml").write_text('[hair]\nsource = "h.xyz"\n')
    with pytest.raises(SceneError, match=r"hair\.source .*\.data/\.usd/\.usda/\.usdc/\.usdz file"):
        load_scene(tmp_path / "s.toml")


@pytest.mark.parametrize("keys", ["scale = 1e19", "translate = [0, -2e18, 0]"])
def test_scale_and_translate_beyond_the_coordinate_bound(tmp_path, keys):
    path = tmp_path / "s.toml"
    path.write_text(f'[hair]\nsource = "furball"\nstrands = 4\n{keys}\n')
    with pytest.raises(
        SceneError,
        match=rf"^{path}: after hair\.scale and hair\.translate, point \d+ = .* lies beyond ±1e\+18",
    ):
        load_scene(path)


def test_procedural_hair_beyond_the_coordinate_bound_names_the_file(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text('[hair]\nsource = "furball"\nstrands = 4\nlength = 1e19\n')
    with pytest.raises(SceneError, match=rf"^{path}: the 'furball' hair: point \d+ = .* lies beyond ±1e\+18"):
        load_scene(path)
