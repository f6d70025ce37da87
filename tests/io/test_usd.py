"""USD BasisCurves (hairjax/_io/_usd.py): stages written by Pixar's own library (`pxr`,
usd-core, the optional extra `usd`) are read; what hairjax writes is read back by `pxr`;
load → save → load keeps points, counts, widths and colours."""

from __future__ import annotations

import importlib.util
import sys

import numpy as np
import pytest

from hairjax._errors import HairFormatError, MissingDependency
from hairjax._io import load_hair, save_hair

needs_usd = pytest.mark.skipif(importlib.util.find_spec("pxr") is None, reason="usd-core is not installed")

RNG = np.random.default_rng(3)
A = np.cumsum(RNG.normal(scale=0.1, size=(9, 3)), axis=0).astype(np.float32)  # curves of 4 and 5
B = np.cumsum(RNG.normal(scale=0.1, size=(6, 3)), axis=0).astype(np.float32)  # curves of 3 and 3


def _curves(stage, path, points, counts):
    from pxr import UsdGeom, Vt

    curves = UsdGeom.BasisCurves.Define(stage, path)
    curves.CreateTypeAttr(UsdGeom.Tokens.linear)
    curves.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(points))
    curves.CreateCurveVertexCountsAttr(Vt.IntArray(list(counts)))
    return curves


def two_prim_stage(path):
    """/groom/a (4 + 5 vertices) under a translated, scaled Xform, with uniform widths and
    vertex colours; /b (3 + 3 vertices) with constant widths, indexed constant colour."""
    from pxr import Gf, Usd, UsdGeom, Vt

    stage = Usd.Stage.CreateNew(str(path))
    groom = UsdGeom.Xform.Define(stage, "/groom")
    groom.AddTranslateOp().Set(Gf.Vec3d(1.0, -2.0, 0.5))
    groom.AddScaleOp().Set(Gf.Vec3f(2.0, 2.0, 2.0))
    a = _curves(stage, "/groom/a", A, [4, 5])
    a.CreateWidthsAttr(Vt.FloatArray([0.01, 0.02]))
    a.SetWidthsInterpolation(UsdGeom.Tokens.uniform)
    a.CreateDisplayColorPrimvar(UsdGeom.Tokens.vertex).Set(Vt.Vec3fArray.FromNumpy(np.abs(A)))
    b = _curves(stage, "/b", B, [3, 3])
    b.CreateWidthsAttr(Vt.FloatArray([0.005]))
    b.SetWidthsInterpolation(UsdGeom.Tokens.constant)
    colour = b.CreateDisplayColorPrimvar(UsdGeom.Tokens.constant)
    colour.Set(Vt.Vec3fArray([(0.9, 0.5, 0.1), (0.2, 0.3, 0.4)]))
    colour.SetIndices(Vt.IntArray([1]))  # indexed: the one value is entry 1
    stage.GetRootLayer().Save()
    return path


def expected_two_prims():
    """The world-space points (translate · scale: p → 2p + t), counts, widths, colours."""
    points = np.concatenate([2.0 * A.astype(np.float64) + [1.0, -2.0, 0.5], B])
    widths = np.concatenate([[0.01] * 4, [0.02] * 5, [0.005] * 6]).astype(np.float32)
    colours = np.concatenate([np.abs(A), np.tile(np.float32([0.2, 0.3, 0.4]), (6, 1))])
    return points, [0, 4, 9, 12, 15], widths, colours


@needs_usd
@pytest.mark.parametrize("suffix", [".usda", ".usdc", ".usd"])
def test_reads_what_pxr_writes(tmp_path, suffix):
    path = two_prim_stage(tmp_path / f"groom{suffix}")
    strands = load_hair(path)
    points, offsets, widths, colours = expected_two_prims()
    # float32 storage, then a float64 transform: one float32 rounding of 2p + t.
    np.testing.assert_allclose(strands.points, points, rtol=0, atol=4 * 2**-24 * 4)
    assert strands.offsets.tolist() == offsets
    assert np.array_equal(strands.attributes["widths"], widths.astype(np.float64))
    assert np.array_equal(strands.color, colours.astype(np.float64))


@needs_usd
def test_reads_a_usdz_package(tmp_path):
    from pxr import UsdUtils

    crate = two_prim_stage(tmp_path / "groom.usdc")
    package = tmp_path / "groom.usdz"
    assert UsdUtils.CreateNewUsdzPackage(str(crate), str(package))
    assert np.array_equal(load_hair(package).points, load_hair(crate).points)


@needs_usd
def test_z_up_time_samples_and_no_colour(tmp_path):
    """A z-up stage (Blender's) turns to y-up; time-sampled points are read at the
    earliest sample; a prim without displayColor leaves `color` None and no widths."""
    from pxr import Usd, UsdGeom, Vt

    stage = Usd.Stage.CreateNew(str(tmp_path / "z.usda"))
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    curves = UsdGeom.BasisCurves.Define(stage, "/hair")
    curves.CreateCurveVertexCountsAttr(Vt.IntArray([2]))
    points = curves.CreatePointsAttr()
    points.Set(Vt.Vec3fArray([(0, 0, 0), (1, 2, 3)]), 5.0)
    points.Set(Vt.Vec3fArray([(0, 0, 0), (7, 7, 7)]), 9.0)
    stage.GetRootLayer().Save()
    strands = load_hair(tmp_path / "z.usda")
    assert strands.points.tolist() == [[0, 0, 0], [1, 3, -2]]  # (x, y, z) → (x, z, −y)
    assert strands.color is None and strands.attributes == {}


@needs_usd
@pytest.mark.parametrize("suffix", [".usda", ".usdc", ".usdz"])
def test_round_trip(tmp_path, suffix):
    first = load_hair(two_prim_stage(tmp_path / "in.usda"))
    path = save_hair(first, tmp_path / f"out{suffix}")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.usda", f"out{suffix}"]  # no temporary left
    again = load_hair(path)
    # Points pass through float32 on writing; read they were float32 values times 2 plus t.
    np.testing.assert_allclose(again.points, first.points, rtol=2**-24, atol=0)
    assert np.array_equal(again.offsets, first.offsets)
    assert np.array_equal(again.attributes["widths"], first.attributes["widths"])
    assert np.array_equal(again.color, first.color)


@needs_usd
def test_pxr_reads_what_hairjax_writes(tmp_path):
    from pxr import Usd, UsdGeom

    first = load_hair(two_prim_stage(tmp_path / "in.usda"))
    stage = Usd.Stage.Open(str(save_hair(first, tmp_path / "out.usda")))
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.y
    curves = UsdGeom.BasisCurves(stage.GetPrimAtPath("/hair"))
    assert curves.GetTypeAttr().Get() == UsdGeom.Tokens.linear
    assert list(curves.GetCurveVertexCountsAttr().Get()) == [4, 5, 3, 3]
    assert np.array_equal(np.asarray(curves.GetPointsAttr().Get()), first.points.astype(np.float32))
    assert curves.GetWidthsInterpolation() == UsdGeom.Tokens.vertex
    assert np.array_equal(
        np.asarray(curves.GetWidthsAttr().Get()), first.attributes["widths"].astype(np.float32)
    )
    colour = curves.GetDisplayColorPrimvar()
    assert colour.GetInterpolation() == UsdGeom.Tokens.vertex
    assert np.array_equal(np.asarray(colour.Get()), first.color.astype(np.float32))


@needs_usd
def test_a_failed_write_leaves_nothing(tmp_path, monkeypatch):
    first = load_hair(two_prim_stage(tmp_path / "in.usda"))
    (tmp_path / "out.usda").write_text("the old file\n")

    def half_written(path, *args):
        path.write_text("#usda 1.0\n(")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("hairjax._io.write_usd", half_written)
    with pytest.raises(OSError, match="No space left"):
        save_hair(first, tmp_path / "out.usda")
    assert (tmp_path / "out.usda").read_text() == "the old file\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.usda", "out.usda"]


def _stage_with(tmp_path, edit):
    from pxr import Usd

    stage = Usd.Stage.CreateNew(str(tmp_path / "bad.usda"))
    edit(stage)
    stage.GetRootLayer().Save()
    return tmp_path / "bad.usda"


def _bad_counts(stage):
    _curves(stage, "/hair", A, [4, 4])


def _no_curves(stage):
    from pxr import UsdGeom

    UsdGeom.Mesh.Define(stage, "/mesh")


def _bad_widths(stage):
    from pxr import UsdGeom, Vt

    curves = _curves(stage, "/hair", A, [4, 5])
    curves.CreateWidthsAttr(Vt.FloatArray([0.1, 0.2, 0.3]))
    curves.SetWidthsInterpolation(UsdGeom.Tokens.vertex)


def _negative_widths(stage):
    from pxr import UsdGeom, Vt

    curves = _curves(stage, "/hair", A, [4, 5])
    curves.CreateWidthsAttr(Vt.FloatArray([0.1, -0.2]))
    curves.SetWidthsInterpolation(UsdGeom.Tokens.uniform)


def _negative_colour(stage):
    from pxr import UsdGeom, Vt

    curves = _curves(stage, "/hair", A, [4, 5])
    curves.CreateDisplayColorPrimvar(UsdGeom.Tokens.uniform).Set(Vt.Vec3fArray([(1, 1, 1), (0, -1, 0)]))


@needs_usd
@pytest.mark.parametrize(
    "edit, message",
    [
        (
            _bad_counts,
            r"/hair: curveVertexCounts \(sum 8, 2 curves\) must be ≥ 1 each and add up to the 9 points",
        ),
        (_no_curves, "the stage has no BasisCurves prim with points"),
        (_bad_widths, "/hair: widths has 3 values, vertex interpolation needs 9"),
        (_negative_widths, r"/hair: the width of point 4 is -0\.2; widths must be finite and > 0"),
        (_negative_colour, r"the colour of point 4 is \(0, -1, 0\)"),
    ],
)
def test_malformed(tmp_path, edit, message):
    path = _stage_with(tmp_path, edit)
    with pytest.raises(HairFormatError, match=rf"^{path}: {message}"):
        load_hair(path)


@needs_usd
def test_not_a_usd_file(tmp_path):
    path = tmp_path / "garbage.usda"
    path.write_bytes(b"\x00\xffnot usd at all")
    with pytest.raises(HairFormatError) as error:
        load_hair(path)
    assert str(error.value) == f"{path}: not a USD stage USD can open: <{path}> is not a valid usda layer"
    with pytest.raises(HairFormatError, match=r"missing\.usdc: cannot read the file: No such file"):
        load_hair(tmp_path / "missing.usdc")


def test_missing_usd_core_names_the_pip_line(tmp_path, monkeypatch):
    for name in [m for m in sys.modules if m == "pxr" or m.startswith("pxr.")]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "pxr", None)  # `import pxr…` raises ImportError
    path = tmp_path / "groom.usda"
    path.write_text("#usda 1.0\n")
    with pytest.raises(MissingDependency, match=r"usd-core.*pip install 'hairjax\[usd\]'"):
        load_hair(path)


@needs_usd
def test_corrupted_text_gives_one_error_or_finite_strands(tmp_path):
    """Seeded byte flips in a .usda (text; USD's own crate reader can crash on flipped bytes
    of a .usdc, so binary files are not fuzzed here): a HairFormatError naming the file, or
    finite strands; never another exception or a numpy warning."""
    data = two_prim_stage(tmp_path / "good.usda").read_bytes()
    rng = np.random.default_rng(17)
    path = tmp_path / "corrupt.usda"
    for _ in range(100):
        corrupted = bytearray(data)
        for at in rng.integers(0, len(data), size=rng.integers(1, 4)):
            corrupted[at] = int(rng.integers(0, 256))
        path.write_bytes(bytes(corrupted))
        try:
            strands = load_hair(path)
        except HairFormatError as error:
            assert str(error).startswith(f"{path}: ")
        else:
            assert np.isfinite(strands.points).all()
