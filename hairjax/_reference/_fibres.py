"""The strands as Mitsuba fibres: control points and radii for `linearcurve` (docs/reference.md).

A `linearcurve` passes through its control points, as hairjax's segments do (docs/model.md
§1), and is a round tube whose radius is interpolated linearly between them. Its diameter
is the ribbon's world width (§5):

- `width_units = "world"`: the strand's `width`, at every point;
- `width_units = "pixels"`: w·D/f at a point of depth D (f the camera's focal length in
  pixels, §2), the world width a camera-facing ribbon needs there to be w pixels wide. The
  projected diameter 2r/D is then w/f along the whole segment (r and D are both linear along
  it), so the fibre covers the ribbon's pixels; its shadows and shading follow that width.

What hairjax does not draw is left out: segments with an endpoint at depth ≤ `camera.near`
(§2) and zero-length segments; a strand is cut where a segment is left out, and pieces of
one point are dropped. Mitsuba closes each curve with a hemisphere of its radius beyond
the end points, where a ribbon stops at them (§5), so each piece's two ends are pulled in
along their segment by their radius (at most a third of the segment): the fibre then ends
where the ribbon does.
"""

from __future__ import annotations

import numpy as np

from .._geometry._projection import camera_view
from .._scene._camera import Camera
from .._scene._strands import Strands

__all__ = ["fibre_curves", "curve_file_text", "END_TRIM_LIMIT"]

# An end is pulled in by its radius, but by no more than this fraction of its segment, so
# that a short piece keeps a third of its length between its two pulled-in ends.
END_TRIM_LIMIT = 1.0 / 3.0


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
    return _trim_ends(points, offsets), offsets


def _trim_ends(points: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """`points` with each piece's first and last point moved inwards along its segment by
    its radius (at most END_TRIM_LIMIT of the segment), the radius interpolated to the new
    point. Both moves are measured on the original points, so a one-segment piece keeps a
    third of its length."""
    out = points.copy()
    for end, inner in ((offsets[:-1], offsets[:-1] + 1), (offsets[1:] - 1, offsets[1:] - 2)):
        step = points[inner] - points[end]
        length = np.linalg.norm(step[:, :3], axis=1)  # > 0: zero-length segments are cut
        t = np.minimum(points[end, 3], END_TRIM_LIMIT * length) / length
        out[end] = points[end] + t[:, None] * step
    return out


def curve_file_text(points: np.ndarray, offsets: np.ndarray) -> str:
    """Mitsuba's curve file: one `x y z radius` line per control point, a blank line between
    curves. Nine significant digits: Mitsuba reads them into float32, which they round-trip."""
    row = "%.9g %.9g %.9g %.9g\n"
    template = "\n".join(row * int(n) for n in np.diff(offsets))
    return template % tuple(points.ravel().tolist())
