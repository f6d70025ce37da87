"""USD hair: `BasisCurves` prims (``.usd``, ``.usda``, ``.usdc``, ``.usdz``), read and
written with Pixar's `usd-core` (``pxr``), the optional extra ``usd``.

Read (`read_usd`): every `BasisCurves` prim the stage's default traversal visits (active,
defined, loaded), in traversal order, each with its world transform
(`UsdGeom.Xformable.ComputeLocalToWorldTransform`), at the earliest authored time (the
first frame of an animation; the default value when there is none). A prim's
`curveVertexCounts` split its `points` into strands. Cubic curves (`type = "cubic"`, any
`basis`) are read as polylines through their control points, which is exact for linear
curves and the control polygon for cubic ones. From each prim, where authored:

- `widths` (USD's curve diameters, world units; constant, uniform = per curve, or
  vertex/varying = per point interpolation) become the per-point attribute "widths";
- `primvars:displayColor` (constant, uniform or vertex/varying; indexed primvars are
  flattened) becomes the per-point colour `Strands.color`.

A stage whose up axis is Z (Blender's default) is turned to hairjax's y-up world:
(x, y, z) → (x, z, −y).

Write (`write_usd`): one linear, non-periodic `BasisCurves` prim `/hair` on a y-up stage,
with `points`, `curveVertexCounts`, the "widths" attribute as vertex-interpolated `widths`
when present, and the colour as vertex-interpolated `primvars:displayColor`. The suffix
chooses the encoding: ``.usda`` text, ``.usdc`` and ``.usd`` binary crate, ``.usdz`` a
package of a crate layer.

The names are those of the USD schema reference for `UsdGeomBasisCurves`,
`UsdGeomCurves` (`widths`) and `UsdGeomGprim` (`displayColor`).
"""

from __future__ import annotations

import functools
import re
from pathlib import Path
from typing import Any

import numpy as np

from .._errors import HairFormatError, MissingDependency
from .._values._strands import first_outside

__all__ = ["read_usd", "write_usd", "USD_SUFFIXES"]

USD_SUFFIXES = (".usd", ".usda", ".usdc", ".usdz")
INSTALL_HINT = "pip install 'hairjax[usd]' (from a checkout: pip install -e '.[usd]')"

# y-up from z-up: a rotation by −90° about x, applied to row vectors (p @ _Z_TO_Y).
_Z_TO_Y = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


def _pxr() -> Any:
    """The `pxr` package, or `MissingDependency` naming the pip line."""
    try:
        import pxr.Tf  # noqa: F401  (imports the submodules used below)
        import pxr.Usd  # noqa: F401
        import pxr.UsdGeom  # noqa: F401
        import pxr.UsdUtils  # noqa: F401
        import pxr.Vt  # noqa: F401
    except ImportError as err:
        raise MissingDependency(
            f"USD hair files need usd-core, which is not installed ({err.msg}): {INSTALL_HINT}"
        ) from err
    import pxr

    return pxr


def read_usd(path) -> dict:
    """The strands of every `BasisCurves` prim of the USD stage at `path` (see the module
    docstring): a dict with `points` (float64 [P, 3]), `offsets` (int64 [S + 1]), `color`
    (float64 [P, 3] or None) and `attributes` ("widths": float64 [P], when authored).

    **Raises:** `MissingDependency` without usd-core; `HairFormatError` naming the file
    (and the prim) when it cannot be opened, holds no curves, or a prim is malformed."""
    pxr = _pxr()
    Usd, UsdGeom = pxr.Usd, pxr.UsdGeom
    path = Path(path)
    try:
        with open(path, "rb"):  # the reason a file cannot be read, in the words of the others
            pass
    except OSError as error:
        raise HairFormatError(path, f"cannot read the file: {error.strerror or error}") from error
    try:
        stage = Usd.Stage.Open(str(path))
    except pxr.Tf.ErrorException as err:  # fires for a file USD cannot parse
        raise HairFormatError(path, f"not a USD stage USD can open: {_tf_message(err)}") from err
    if stage is None:  # fires when USD declines the file without raising
        raise HairFormatError(path, "not a USD stage USD can open")
    z_up = UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.z
    time = Usd.TimeCode.EarliestTime()
    parts = []
    for prim in stage.Traverse():
        if prim.IsA(UsdGeom.BasisCurves):
            fail = functools.partial(_fail, path, prim)
            try:
                part = _read_prim(UsdGeom.BasisCurves(prim), time, fail)
            except (TypeError, ValueError) as err:  # a value of the wrong type (not a HairFormatError)
                if isinstance(err, HairFormatError):
                    raise
                fail(f"an attribute holds a value of the wrong type ({err})")
            if part is not None:
                parts.append(part)
    if not parts:
        raise HairFormatError(path, "the stage has no BasisCurves prim with points")
    points = np.concatenate([p["points"] for p in parts])
    if z_up:
        points = points @ _Z_TO_Y
    counts = np.concatenate([p["counts"] for p in parts])
    offsets = np.concatenate([[0], np.cumsum(counts)])
    attributes = {}
    if any(p["widths"] is not None for p in parts):
        if not all(p["widths"] is not None for p in parts):
            raise HairFormatError(path, "some BasisCurves prims have widths and others not")
        attributes["widths"] = np.concatenate([p["widths"] for p in parts])
    color = None
    if any(p["color"] is not None for p in parts):
        # A prim without displayColor is white, the colour hairjax takes for hair without one.
        color = np.concatenate(
            [np.ones((len(p["points"]), 3)) if p["color"] is None else p["color"] for p in parts]
        )
    return {"points": points, "offsets": offsets, "color": color, "attributes": attributes}


def _fail(path, prim, problem: str):
    raise HairFormatError(path, f"{prim.GetPath()}: {problem}")


def _tf_message(err: Exception) -> str:
    """The message of USD's first error, without the C++ function, file and line that
    precede it (`Error in 'f' at line n in file x.cpp : 'message'`)."""
    first = next((line.strip() for line in str(err).splitlines() if line.strip()), type(err).__name__)
    match = re.search(r"^Error in .* : '(.*?)'?$", first)
    return match.group(1) if match else first


def _read_prim(curves, time, fail) -> dict | None:
    """One prim's world-space points, vertex counts, per-point widths and colours (or None
    for each that is not authored); None for a prim without points."""
    points = curves.GetPointsAttr().Get(time)
    if points is None or len(points) == 0:
        return None
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    counts = curves.GetCurveVertexCountsAttr().Get(time)
    counts = np.asarray([] if counts is None else counts, dtype=np.int64)
    if counts.size == 0 or np.any(counts < 1) or counts.sum() != len(points):
        fail(
            f"curveVertexCounts (sum {int(counts.sum())}, {counts.size} curves) must be ≥ 1 each "
            f"and add up to the {len(points)} points"
        )
    matrix = np.asarray(curves.ComputeLocalToWorldTransform(time), dtype=np.float64)
    if not (np.isfinite(points).all() and np.isfinite(matrix).all()):
        fail("its points or its transform hold a NaN or infinite value")
    # Points within the coordinate bound and a finite transform: the product is finite
    # unless the transform scales beyond it, which Strands then refuses naming the point.
    with np.errstate(over="ignore", invalid="ignore"):
        points = points @ matrix[:3, :3] + matrix[3, :3]  # USD's row vectors: p · M
    widths = curves.GetWidthsAttr().Get(time)
    if widths is not None:
        widths = _per_point(
            np.asarray(widths, np.float64), curves.GetWidthsInterpolation(), counts, "widths", fail
        )
        outside = first_outside(widths, lo=0.0, lo_open=True)  # docs/scenes.md "Input ranges"
        if outside is not None:
            fail(f"the width of point {outside} is {widths[outside]:g}; widths must be finite and > 0")
    color = None
    primvar = curves.GetDisplayColorPrimvar()
    if primvar.HasAuthoredValue():
        values = np.asarray(primvar.ComputeFlattened(time), np.float64).reshape(-1, 3)
        color = _per_point(values, primvar.GetInterpolation(), counts, "primvars:displayColor", fail)
    return {"points": points, "counts": counts, "widths": widths, "color": color}


def _per_point(values: np.ndarray, interpolation: str, counts: np.ndarray, name: str, fail) -> np.ndarray:
    """`values` of a primvar expanded to one row per point."""
    expected = {
        "constant": 1,
        "uniform": len(counts),
        "vertex": int(counts.sum()),
        "varying": int(counts.sum()),  # linear curves; for cubic ones see below
    }
    if interpolation not in expected:
        fail(f"{name} has interpolation {interpolation!r}; read are {', '.join(expected)}")
    if len(values) != expected[interpolation]:
        extra = " (varying values on cubic curves are not read)" if interpolation == "varying" else ""
        needs = expected[interpolation]
        fail(f"{name} has {len(values)} values, {interpolation} interpolation needs {needs}{extra}")
    if interpolation == "constant":
        return np.repeat(values, int(counts.sum()), axis=0)
    if interpolation == "uniform":
        return np.repeat(values, counts, axis=0)
    return values


def write_usd(path, points: np.ndarray, offsets: np.ndarray, color, widths) -> None:
    """Write strands as one linear `BasisCurves` prim `/hair` (see the module docstring);
    `color` (float [P, 3]) and `widths` (float [P]) may be None. `path`'s suffix picks
    the encoding; the file is written in place (the caller makes it atomic)."""
    pxr = _pxr()
    Usd, UsdGeom, Vt = pxr.Usd, pxr.UsdGeom, pxr.Vt
    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    curves = UsdGeom.BasisCurves.Define(stage, "/hair")
    stage.SetDefaultPrim(curves.GetPrim())
    curves.CreateTypeAttr(UsdGeom.Tokens.linear)
    curves.CreateWrapAttr(UsdGeom.Tokens.nonperiodic)
    curves.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(np.asarray(points, np.float32)))
    curves.CreateCurveVertexCountsAttr(Vt.IntArray.FromNumpy(np.diff(offsets).astype(np.int32)))
    if widths is not None:
        curves.CreateWidthsAttr(Vt.FloatArray.FromNumpy(np.asarray(widths, np.float32)))
        curves.SetWidthsInterpolation(UsdGeom.Tokens.vertex)
    if color is not None:
        primvar = curves.CreateDisplayColorPrimvar(UsdGeom.Tokens.vertex)
        primvar.Set(Vt.Vec3fArray.FromNumpy(np.asarray(color, np.float32)))
    path = Path(path)
    if path.suffix.lower() != ".usdz":
        stage.GetRootLayer().Export(str(path))
        return
    # A .usdz is a zip package of layers: write a crate layer beside it, then package it.
    crate = path.with_name(path.name + ".usdc")
    try:
        stage.GetRootLayer().Export(str(crate))
        if not pxr.UsdUtils.CreateNewUsdzPackage(str(crate), str(path)):
            raise OSError(f"{path}: USD could not write the .usdz package")
    finally:
        crate.unlink(missing_ok=True)
