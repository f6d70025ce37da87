"""The strands as Mitsuba fibres: control points and radii for `bsplinecurve` (docs/reference.md).

The fibres are cubic B-splines whose every control point is repeated three times, the
outer copies moved 1 % of the way towards the neighbouring points. Such a curve is the
polyline, as hairjax's segments are (docs/model.md §1), with the radius linear along it:
away from the corners each piece of the spline weighs points of one segment only, so it
runs straight along it; it rounds each corner, off the polyline by at most 0.2 % of a
segment (`tests/reference/test_fibres.py`). Not
`linearcurve`, which is the same tube: Mitsuba 3.9.1's `linearcurve` sets only the
shading frame's normal, so the frame's tangent, which the `hair` BSDF reads as the
fibre's axis (its plugin says it assumes `bsplinecurve`'s frame), is an arbitrary
direction about that normal. Measured on a fibre leaning 17° in the image plane: the
frame's tangent is (0, 1, 0) and the BSDF's value off by a factor up to 2.5 lit from
behind; `bsplinecurve`'s frame has the fibre's tangent (docs/reference.md, "Why
B-splines").

The diameter is the ribbon's world width (§5):
- `width_units = "world"`: the strand's `width`, at every point;
- `width_units = "pixels"`: w·D/f at a point of depth D (f the camera's focal length in
  pixels, §2), the world width a camera-facing ribbon needs there to be w pixels wide. The
  projected diameter 2r/D is then w/f along the whole segment (r and D are both linear along
  it), so the fibre covers the ribbon's pixels; its shadows and shading follow that width.
What hairjax does not draw is left out: segments with an endpoint at depth ≤ `camera.near`
(§2) and zero-length segments; a strand is cut where a segment is left out, and pieces of
one point are dropped. The ends are Mitsuba's: past each end point a `bsplinecurve`
reaches about half its radius further (measured: 1.6 px on a fibre 6 px wide, seen
square-on), a share of a pixel on the 1–2 px fibres of a hair, where a ribbon stops at the
point (docs/reference.md, "The mapping").
"""

from __future__ import annotations

import numpy as np

from .._geometry._projection import camera_view
from .._values._camera import Camera
from .._values._strands import Strands

__all__ = ["fibre_curves", "bspline_control_points", "curve_file_text", "REPEATS", "SPREAD"]

# Each point is a B-spline control point this many times: a cubic B-spline piece weighs
# four consecutive control points, so with three copies of each, every piece holds at
# most two distinct points and runs straight between them.
REPEATS = 3
# How far the outer copies move towards the neighbouring points: exact copies make the
# curve's derivative 0 at the points, where Mitsuba 3.9.1 crashed (a segmentation fault in
# `render`: Sintel's side view of experiment 14 at sample seed 1). Moved, a piece near a
# corner holds points of two segments, so the curve rounds it, off the polyline by at most
# a quarter of this share of a segment, and is straight elsewhere.
SPREAD = 0.01


def fibre_curves(strands: Strands, camera: Camera) -> tuple[np.ndarray, np.ndarray]:
    """The fibres as curves, for every piece of a strand that hairjax draws (module
    docstring): (`float64[P, 4]` control points x, y, z, radius, piece after piece;
    `int64[C + 1]` offsets, piece c being rows offsets[c] … offsets[c + 1] − 1, each ≥ 2)."""
    view = camera_view(camera)
    _, depth = view.project(strands.points)
    width = np.asarray(strands.width, dtype=np.float64)[strands.strand_of_point]
    if strands.width_units == "world":
        radius = 0.5 * width
    else:  # pixels: the world width that is w pixels wide at the point's depth (§5 inverted)
        radius = 0.5 * width * depth / view.focal
    rows = np.column_stack([strands.points, radius])
    a, b = strands.segments().T
    drawn = (depth[a] > camera.near) & (depth[b] > camera.near)
    drawn &= np.any(strands.points[a] != strands.points[b], axis=1)
    a, b = a[drawn], b[drawn]
    # A drawn segment starts a piece unless the drawn segment before it, of the same strand,
    # ends where it starts (the same point, or a repeated one: a zero-length segment between).
    strand = strands.strand_of_point
    starts = np.ones(len(a), dtype=bool)
    moved = np.any(strands.points[b[:-1]] != strands.points[a[1:]], axis=1)
    starts[1:] = (strand[b[:-1]] != strand[a[1:]]) | moved
    first = np.flatnonzero(starts)
    counts = np.diff(np.append(first, len(a))) + 1  # points per piece: its segments + 1
    offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    # Each piece's points: its first segment's start, then every segment's end.
    index = np.stack([np.where(starts, a, -1), b], axis=1).ravel()
    points = rows[index[index >= 0]]
    return points, offsets


def bspline_control_points(points: np.ndarray, offsets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """`fibre_curves`' polylines as `bsplinecurve` control points (module docstring): each
    point `REPEATS` times, the first copy moved `SPREAD` of the way towards the point before
    it and the last towards the point after it (a piece's end points stay). Returns
    (control points, offsets) in `fibre_curves`' form."""
    index = np.arange(len(points))
    piece = np.searchsorted(offsets, index, side="right") - 1
    before = np.maximum(index - 1, offsets[piece])
    after = np.minimum(index + 1, offsets[piece + 1] - 1)
    copies = [points + SPREAD * (points[before] - points), points, points + SPREAD * (points[after] - points)]
    return np.stack(copies, axis=1).reshape(-1, points.shape[1]), np.asarray(offsets) * REPEATS


def curve_file_text(points: np.ndarray, offsets: np.ndarray) -> str:
    """Mitsuba's curve file: one `x y z radius` line per control point, a blank line between
    curves. Nine significant digits: Mitsuba reads them into float32, which they round-trip."""
    row = "%.9g %.9g %.9g %.9g\n"
    template = "\n".join(row * int(n) for n in np.diff(offsets))
    return template % tuple(points.ravel().tolist())
