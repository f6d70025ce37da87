"""The occluder's surface at a raster's pixel centres (docs/model.md §9, §13).

Geometry only, NumPy float64. `occluder_hits(view, occluder)` gives per pixel centre of
`view` (the camera, or the light for the occluder's shadow) the first surface point along
the pixel's ray: its depth along the view axis (inf where the ray misses), the unit
outward normal and the point. The sphere is ray-cast; a mesh is rasterised:

- a triangle is drawn only if its three vertices lie beyond the view's near plane
  (perspective views; every triangle for orthographic ones), and not if its projection
  has zero area;
- a pixel centre c belongs to a triangle when its screen-space barycentric coordinates
  λ (from edge functions) are all ≥ 0 (edges included; GL's top-left rule differs only on
  edges, where docs/model.md §11's band holds the pixel);
- attributes are interpolated perspective-correctly, λ'_i = (λ_i/D_i)/Σ_j(λ_j/D_j)
  (linearly for orthographic views): the point P = Σ λ'_i V_i is where the ray meets the
  triangle's plane, its depth D = (P − origin)·forward (1/D is linear in screen space,
  as for hair fragments, §5), the normal normalise(Σ λ'_i N_i) with the vertex normals N;
- the nearest triangle wins (z-buffer; a tie at equal depth is an edge shared by two
  triangles, where both give the same point).

`occluder_visibility` is the occluder's shadow: a light-view depth test (§13).
"""

from __future__ import annotations

import numpy as np

from .._constants import OCCLUDER_SHADOW_BIAS
from ._projection import View, light_view

__all__ = [
    "occluder_hits",
    "sphere_hits",
    "mesh_hits",
    "vertex_normals",
    "occluder_extent",
    "occluder_light_view",
    "occluder_visibility",
    "shadow_bias",
    "silhouette_pixels",
    "interpolation_bound",
    "corner_nudges",
    "box_candidates",
    "perspective_correct",
]

_CHUNK = 1 << 22  # (triangle, pixel) candidates per batch: bounds memory to ~1 GB


def _unit(v: np.ndarray) -> np.ndarray:
    norm = np.linalg.norm(v, axis=-1, keepdims=True)
    # Fires for zero vectors (a vertex of degenerate triangles only): no normal, no light.
    return np.where(norm > 0, v / np.where(norm > 0, norm, 1.0), 0.0)


def occluder_hits(view: View, occluder):
    """Per pixel centre of `view` (row-major): (depth `[H*W]`, inf where nothing is hit;
    unit normal `[H*W, 3]`; point `[H*W, 3]`)."""
    if occluder.kind == "sphere":
        return sphere_hits(view, occluder)
    return mesh_hits(view, occluder.vertices, occluder.triangles)


def sphere_hits(view: View, occluder):
    """Per pixel centre: view depth of the first hit on the sphere (inf if none), normal, point."""
    origin, direction = view.pixel_rays()
    centre = np.asarray(occluder.center, dtype=np.float64)
    oc = origin - centre
    b = np.sum(oc * direction, axis=1)
    c = np.sum(oc * oc, axis=1) - occluder.radius**2
    disc = b * b - c
    # Fires for rays that miss the sphere (disc < 0): sqrt(0), not NaN; `hit` drops them.
    root = np.sqrt(np.where(disc >= 0, disc, 0.0))
    if view.perspective:
        # The nearer intersection in front of the eye; the farther one when the eye is inside.
        t = np.where(-b - root > 0, -b - root, -b + root)
        hit = (disc >= 0) & (t > 0)
    else:
        # Orthographic (a directional light's view): rays run through the whole scene,
        # their origins on the plane through the view's centre, so t may be negative.
        t = -b - root
        hit = disc >= 0
    point = origin + t[:, None] * direction
    depth = np.where(hit, (point - view.origin) @ view.forward, np.inf)
    # _unit's zero branch cannot fire here: hits lie at the radius, misses farther out.
    normal = _unit(point - centre)
    return depth, normal, point


def vertex_normals(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Area-weighted mean of the adjacent faces' normals (right-hand rule: counter-clockwise
    seen from outside is outward, OBJ's convention), `float64[V, 3]`."""
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    face = np.cross(b - a, c - a)  # length 2·area: the area weighting
    total = np.zeros_like(vertices)
    for k in range(3):
        np.add.at(total, triangles[:, k], face)
    return _unit(total)


def drawable_triangles(view: View, vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Indices of the triangles the view draws: all three vertices beyond its near plane
    (every triangle for orthographic views). Shared with the GL renderer."""
    if not view.perspective:
        return np.arange(len(triangles))
    _, depth = view.project(vertices)
    return np.flatnonzero(np.all(depth[triangles] > view.near, axis=1))


def mesh_hits(view: View, vertices: np.ndarray, triangles: np.ndarray, normals=None):
    """The mesh rasterised at `view`'s pixel centres (module docstring): as `sphere_hits`."""
    depth, normal, point, _ = _mesh_raster(view, vertices, triangles, normals)
    return depth, normal, point


def _mesh_raster(view: View, vertices: np.ndarray, triangles: np.ndarray, normals=None):
    """`mesh_hits` and, per pixel, the winning triangle's index into `triangles` (−1: none)."""
    w, h = view.width, view.height
    depth_out = np.full(w * h, np.inf)
    normal_out = np.zeros((w * h, 3))
    point_out = np.zeros((w * h, 3))
    normals = vertex_normals(vertices, triangles) if normals is None else normals
    drawn = drawable_triangles(view, vertices, triangles)
    tri = triangles[drawn]
    xy, depth = view.project(vertices)
    best_depth = depth_out
    best_tri = np.full(w * h, -1, np.int64)
    best_lam = np.zeros((w * h, 3))
    for k, pixel, lam in pixel_fragments(view, xy, depth, tri):
        point = np.einsum("ni,nij->nj", lam, vertices[tri[k]])
        d = (point - view.origin) @ view.forward
        # Nearest per pixel within the batch, then against the earlier batches.
        order = np.lexsort((d, pixel))
        first = np.ones(order.size, bool)
        first[1:] = pixel[order][1:] != pixel[order][:-1]
        sel = order[first]
        closer = d[sel] < best_depth[pixel[sel]]
        sel = sel[closer]
        best_depth[pixel[sel]] = d[sel]
        best_tri[pixel[sel]] = k[sel]
        best_lam[pixel[sel]] = lam[sel]
    hit = np.flatnonzero(best_tri >= 0)
    corners3 = tri[best_tri[hit]]
    point_out[hit] = np.einsum("ni,nij->nj", best_lam[hit], vertices[corners3])
    normal_out[hit] = _unit(np.einsum("ni,nij->nj", best_lam[hit], normals[corners3]))
    winner = np.full(w * h, -1, np.int64)
    winner[hit] = drawn[best_tri[hit]]
    return best_depth, normal_out, point_out, winner


def box_candidates(x0: np.ndarray, y0: np.ndarray, nx: np.ndarray, count: np.ndarray):
    """Every pixel of each triangle's bounding box, in batches of at most _CHUNK: triangle
    k's box has `count[k]` pixels (`nx[k]` per row, 0 to drop it), row-major from (x0[k],
    y0[k]). Yields (k `[N]`, px `[N]`, py `[N]`)."""
    tri_of = np.repeat(np.arange(len(count)), count)
    within = np.arange(tri_of.size) - np.repeat(np.cumsum(count) - count, count)
    for lo in range(0, tri_of.size, _CHUNK):
        k, r = tri_of[lo : lo + _CHUNK], within[lo : lo + _CHUNK]
        yield k, x0[k] + r % nx[k], y0[k] + r // nx[k]


def perspective_correct(lam: np.ndarray, vertex_depth: np.ndarray) -> np.ndarray:
    """Screen-space barycentrics `[N, 3]` made perspective-correct: λ'_i ∝ λ_i / D_i with
    `vertex_depth` `[N, 3]` the triangles' vertex depths, normalised to sum to 1."""
    lam = lam / vertex_depth
    return lam / lam.sum(axis=1, keepdims=True)


def pixel_fragments(view: View, xy: np.ndarray, depth: np.ndarray, tri: np.ndarray):
    """Every (triangle, pixel centre) pair where the centre lies in the projected triangle
    (module docstring: λ ≥ 0, edges included, zero-area projections dropped), in batches of
    at most _CHUNK candidates: yields (k: index into `tri` `[N]`, pixel `[N]`, λ' `[N, 3]`
    perspective-correct for perspective views). `xy`, `depth`: `view.project(vertices)`."""
    w, h = view.width, view.height
    a, b, c = (xy[tri[:, k]] for k in range(3))
    area = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    corners = xy[tri]
    # Pixel columns i whose centre i + ½ lies in [min x, max x], clipped to the image.
    x0 = np.clip(np.ceil(corners[..., 0].min(axis=1) - 0.5), 0, w)
    x1 = np.clip(np.floor(corners[..., 0].max(axis=1) - 0.5), -1, w - 1)
    y0 = np.clip(np.ceil(corners[..., 1].min(axis=1) - 0.5), 0, h)
    y1 = np.clip(np.floor(corners[..., 1].max(axis=1) - 0.5), -1, h - 1)
    nx = np.maximum(x1 - x0 + 1, 0).astype(np.int64)
    ny = np.maximum(y1 - y0 + 1, 0).astype(np.int64)
    # Zero-area projections (edge-on triangles) cover no pixel centre's open set: dropped.
    count = np.where(area != 0, nx * ny, 0)
    for k, px, py in box_candidates(x0, y0, nx, count):
        cx, cy = px + 0.5, py + 0.5
        ak, bk, ck = a[k], b[k], c[k]
        # Barycentrics from edge functions, each over the signed area: both windings.
        lam_a = ((bk[:, 0] - cx) * (ck[:, 1] - cy) - (bk[:, 1] - cy) * (ck[:, 0] - cx)) / area[k]
        lam_b = ((ck[:, 0] - cx) * (ak[:, 1] - cy) - (ck[:, 1] - cy) * (ak[:, 0] - cx)) / area[k]
        lam_c = 1.0 - lam_a - lam_b
        lam = np.stack([lam_a, lam_b, lam_c], axis=1)
        inside = np.all(lam >= 0, axis=1)
        k, lam = k[inside], lam[inside]
        pixel = (py[inside] * w + px[inside]).astype(np.int64)
        if view.perspective:
            lam = perspective_correct(lam, depth[tri[k]])
        yield k, pixel, lam


def occluder_extent(occluder) -> np.ndarray:
    """Points whose bounding box holds the occluder (`[K, 3]`): a mesh's vertices, the
    sphere's bounding-box corners."""
    if occluder.kind == "mesh":
        return occluder.vertices
    corners = np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1])).reshape(3, -1).T
    return np.asarray(occluder.center) + occluder.radius * corners


def occluder_light_view(light, points: np.ndarray, occluder, resolution: int) -> View:
    """The light's view for the occluder's shadow: `light_view` framing the strand points
    and the occluder together, R × R, one texel of margin (shared by both renderers)."""
    return light_view(light, np.concatenate([points, occluder_extent(occluder)]), resolution, 1)


def shadow_bias(view: View, depth: np.ndarray) -> np.ndarray:
    """OCCLUDER_SHADOW_BIAS texels in world units at light depth `depth`: 1/focal per texel
    orthographic, depth/focal perspective."""
    scale = depth if view.perspective else np.ones_like(depth)
    return OCCLUDER_SHADOW_BIAS * scale / view.focal


def occluder_visibility(view: View, depth_map: np.ndarray, points: np.ndarray) -> np.ndarray:
    """1 where the light reaches `points` past the occluder, 0 where the occluder is
    nearer the light (`float64[Q]`): the point's light depth z against the map's depth at
    the texel ⌊xy⌋ it falls in, z > map + bias is shadowed. Points outside the map, or
    behind a point light's near plane, are lit."""
    r = view.width
    xy, z = view.project(points)
    # Clip before the cast: points far outside (near a point light's plane) stay outside.
    tx = np.floor(np.clip(xy[:, 0], -1, r)).astype(np.int64)
    ty = np.floor(np.clip(xy[:, 1], -1, r)).astype(np.int64)
    inside = (tx >= 0) & (tx < r) & (ty >= 0) & (ty < r)
    if view.perspective:
        inside &= z > view.near
    blocker = depth_map[np.where(inside, ty * r + tx, 0)]
    shadowed = inside & (z > blocker + shadow_bias(view, z))
    return np.where(shadowed, 0.0, 1.0)


def silhouette_pixels(view: View, occluder, delta: float) -> np.ndarray:
    """Pixels (`bool[H*W]`) whose centre lies within `delta` pixels of a place where the
    occluder's coverage or surface jumps in `view`: for the sphere, its outline (the
    ray's discriminant within 1e-4 r² of 0); for a mesh, its drawn triangles' edges
    except those shared by exactly two drawn triangles lying on opposite sides of the
    edge (there the surface continues across, and either triangle gives the same point).
    For docs/model.md §11's band: float32 may put such a pixel centre on the other side."""
    w, h = view.width, view.height
    if occluder.kind == "sphere":
        origin, direction = view.pixel_rays()
        oc = origin - np.asarray(occluder.center)
        b = np.sum(oc * direction, axis=1)
        disc = b * b - (np.sum(oc * oc, axis=1) - occluder.radius**2)
        return np.abs(disc) < 1e-4 * occluder.radius**2
    tri = occluder.triangles[drawable_triangles(view, occluder.vertices, occluder.triangles)]
    xy, _ = view.project(occluder.vertices)
    edges = np.concatenate([tri[:, [0, 1, 2]], tri[:, [1, 2, 0]], tri[:, [2, 0, 1]]])  # (a, b, opposite)
    key = np.sort(edges[:, :2], axis=1)
    order = np.lexsort((key[:, 1], key[:, 0]))
    key, edges = key[order], edges[order]
    start = np.r_[True, np.any(key[1:] != key[:-1], axis=1)]
    group = np.cumsum(start) - 1
    count = np.bincount(group)[group]

    def side(e):
        a, b, c = xy[e[:, 0]], xy[e[:, 1]], xy[e[:, 2]]
        return np.sign((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))

    s = side(np.column_stack([key, edges[:, 2]]))  # the opposite vertex's side of a → b (sorted)
    # A pair is continuous when its two opposite vertices lie strictly on opposite sides.
    pair_sum = np.bincount(group, s)[group]
    continuous = (count == 2) & (pair_sum == 0) & (s != 0)
    seg = key[start & ~continuous]  # one row per edge; continuity is the same for both rows
    return _near_segments(xy[seg[:, 0]], xy[seg[:, 1]], delta, w, h)


def _near_segments(p0: np.ndarray, p1: np.ndarray, delta: float, w: int, h: int) -> np.ndarray:
    """Pixels whose centre lies within `delta` of one of the segments p0 → p1."""
    out = np.zeros(w * h, bool)
    x0 = np.clip(np.ceil(np.minimum(p0[:, 0], p1[:, 0]) - delta - 0.5), 0, w)
    x1 = np.clip(np.floor(np.maximum(p0[:, 0], p1[:, 0]) + delta - 0.5), -1, w - 1)
    y0 = np.clip(np.ceil(np.minimum(p0[:, 1], p1[:, 1]) - delta - 0.5), 0, h)
    y1 = np.clip(np.floor(np.maximum(p0[:, 1], p1[:, 1]) + delta - 0.5), -1, h - 1)
    nx = np.maximum(x1 - x0 + 1, 0).astype(np.int64)
    ny = np.maximum(y1 - y0 + 1, 0).astype(np.int64)
    k = np.repeat(np.arange(len(p0)), nx * ny)
    r = np.arange(k.size) - np.repeat(np.cumsum(nx * ny) - nx * ny, nx * ny)
    px, py = x0[k] + r % nx[k], y0[k] + r // nx[k]
    c = np.stack([px + 0.5, py + 0.5], axis=1)
    d = p1[k] - p0[k]
    length2 = np.sum(d * d, axis=1)
    # Fires for zero-length edges (coincident vertices): the distance to the point p0.
    t = np.clip(np.sum((c - p0[k]) * d, axis=1) / np.where(length2 > 0, length2, 1.0), 0.0, 1.0)
    near = np.linalg.norm(c - (p0[k] + t[:, None] * d), axis=1) <= delta
    out[(py[near] * w + px[near]).astype(np.int64)] = True
    return out


def interpolation_bound(view: View, occluder, light, step: float) -> np.ndarray:
    """Per pixel (`float[H*W]`), how far the mesh's lit colour k·light·max(N·L, 0) may
    move when the winning triangle's projected vertices move by up to `step` pixels per
    axis (llvmpipe rounds them to 1/256 px, and its attribute interpolation follows): the
    first-order bound Σ over the 6 coordinates of |∂colour/∂coordinate|·step, derivatives
    by central differences of the barycentric interpolation (module docstring), times
    max(k·light). Matters for triangles much smaller than a pixel, where the barycentrics
    move by step/altitude. 0 off the mesh and for a sphere."""
    w, h = view.width, view.height
    out = np.zeros(w * h)
    if occluder.kind == "sphere":
        return out
    vertices, triangles = occluder.vertices, occluder.triangles
    normals = vertex_normals(vertices, triangles)
    _, _, point, winner = _mesh_raster(view, vertices, triangles, normals)
    pix = np.flatnonzero(winner >= 0)
    tri = triangles[winner[pix]]
    xy, depth = view.project(vertices)
    corners = xy[tri]  # [Q, 3, 2]
    c = np.stack([pix % w + 0.5, pix // w + 0.5], axis=1)
    if light.kind == "directional":
        to_l = -np.asarray(light.direction, np.float64) / np.linalg.norm(light.direction)
        to_l = np.broadcast_to(to_l, point[pix].shape)
    else:
        to_l = _unit(np.asarray(light.position, np.float64) - point[pix])

    def lambert(p):
        a, b, cc = p[:, 0], p[:, 1], p[:, 2]
        area = (b[:, 0] - a[:, 0]) * (cc[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (cc[:, 0] - a[:, 0])
        la = ((b[:, 0] - c[:, 0]) * (cc[:, 1] - c[:, 1]) - (b[:, 1] - c[:, 1]) * (cc[:, 0] - c[:, 0])) / area
        lb = ((cc[:, 0] - c[:, 0]) * (a[:, 1] - c[:, 1]) - (cc[:, 1] - c[:, 1]) * (a[:, 0] - c[:, 0])) / area
        lam = np.stack([la, lb, 1 - la - lb], axis=1)
        if view.perspective:
            lam = lam / depth[tri]
            lam /= lam.sum(axis=1, keepdims=True)
        n = _unit(np.einsum("ni,nij->nj", lam, normals[tri]))
        return np.maximum(np.sum(n * to_l, axis=1), 0.0)

    bound = np.zeros(len(pix))
    for up, down in corner_nudges(corners, step):
        bound += 0.5 * np.abs(lambert(up) - lambert(down))
    out[pix] = float(np.max(np.asarray(occluder.color) * np.asarray(light.color))) * bound
    return out


def corner_nudges(corners: np.ndarray, step: float):
    """For `[T, 3, 2]` screen-space triangle corners: each of the six coordinates moved by
    +step and by −step, the others kept, as (up, down) pairs — the terms of a first-order
    bound on what snapping vertices to a grid of `step` can change."""
    for i in range(3):
        for axis in range(2):
            up, down = corners.copy(), corners.copy()
            up[:, i, axis] += step
            down[:, i, axis] -= step
            yield up, down
