"""Hair patches and slide 17's four passes (docs/model.md §18): hand-built cases whose
colours follow from the rule by hand, the strand texture, GL's rounding of vertices to
1/256 px measured, the JAX rule against GL, the patch mesh and the example scene."""

import dataclasses

import jax.numpy as jnp
import numpy as np
import pytest
from helpers import EXAMPLES

import hairjax as hj
from hairjax import Camera, PatchGeometry
from hairjax._constants import PATCH_OPAQUE_EPS, PATCH_OPAQUE_STRANDS, RASTER_SUBPIXEL_BITS
from hairjax._errors import SceneError
from hairjax._geometry._occluder import _near_segments
from hairjax._geometry._ordering import hair_centre
from hairjax._geometry._projection import View, camera_view
from hairjax._patches import (
    Patches,
    composite_patches,
    four_pass_weights,
    patch_alpha,
    patch_fragments,
    patch_mesh,
    patch_texture,
    scene_patches,
    strand_hash,
)
from hairjax._shading._scheuermann_inputs import strand_normals
from hairjax._values._strands import tangents

BG = np.array([0.1, 0.2, 0.3])
RED, GREEN, BLUE = np.eye(3)
# Core 0: a(u) = 1 − |2u − 1|, so u sets a quad's (constant) alpha: u = ½ → 1 (opaque).
A_HALF, A_FIFTH = 0.25, 0.1  # u for a = 0.5 and a = 0.2


def _view(size=8):
    return camera_view(Camera(eye=(0.0, 0.0, 4.0), fov=40.0, width=size, height=size))


def _quads(specs):
    """Axis-aligned rectangles covering the view's centre, one per (z, u, front), drawn in
    the given order; quad q carries point colour q. Front: counter-clockwise seen from +z.
    Off-centre corners keep the diagonal and sides away from pixel centres."""
    vertices, triangles, us = [], [], []
    for q, (z, u, front) in enumerate(specs):
        base = 4 * q
        vertices += [(-1.03, -0.97, z), (1.21, -0.97, z), (1.21, 1.13, z), (-1.03, 1.13, z)]
        us += [u] * 4
        tris = [(0, 1, 2), (0, 2, 3)] if front else [(0, 2, 1), (0, 3, 2)]
        triangles += [(base + a, base + b, base + c) for a, b, c in tris]
    n = len(specs)
    return Patches(
        np.array(vertices, float), np.array(triangles), np.array(us, float), np.repeat(np.arange(n), 4), 0.0
    )


def _jax_image(view, patches, colors):
    frags = patch_fragments(view, patches)
    weights = four_pass_weights(frags, view.width * view.height)
    return np.asarray(
        composite_patches(frags, weights, jnp.asarray(colors), jnp.asarray(BG), view.height, view.width)
    )


def _centre_pixel(image):
    h, w = image.shape[:2]
    return image[h // 2, w // 2]


def over(a, c, behind):
    return a * c + (1 - a) * behind


# (specs in draw order, colours, expected RGB at the centre): each by slide 17's passes.
CASES = {
    # Opaque red nearer than a transparent green: the green fails Z LESS in pass 4.
    "opaque-over-transparent": ([(0.5, 0.5, True), (0.0, A_HALF, True)], [RED, GREEN], RED),
    # A transparent back face behind the opaque red: pass 3's Z test LESS against Z₁.
    "opaque-over-back": ([(0.5, 0.5, True), (0.0, A_HALF, False)], [RED, GREEN], RED),
    # A transparent green in front of the opaque red: blended over it in pass 4.
    "transparent-over-opaque": ([(0.0, 0.5, True), (0.5, A_HALF, True)], [RED, GREEN], over(0.5, GREEN, RED)),
    # Front (green, near) drawn first, back (blue, far) second: pass 3 draws the back face
    # before pass 4 draws the front one, whatever the draw order.
    "back-then-front": (
        [(0.5, A_HALF, True), (0.0, A_FIFTH, False)],
        [GREEN, BLUE],
        over(0.5, GREEN, over(0.2, BLUE, BG)),
    ),
    # Two front faces, the near one drawn first: it writes Z, the far one is rejected.
    "front-near-first": ([(0.5, A_HALF, True), (0.0, A_FIFTH, True)], [GREEN, BLUE], over(0.5, GREEN, BG)),
    # The far one drawn first: both pass, in draw order.
    "front-far-first": (
        [(0.0, A_FIFTH, True), (0.5, A_HALF, True)],
        [BLUE, GREEN],
        over(0.5, GREEN, over(0.2, BLUE, BG)),
    ),
    # Two back faces, near first: Z writes are off in pass 3, so both blend, in draw order
    # (the far one over the near one: the order dependence the static sort keeps small).
    "back-near-first": (
        [(0.5, A_HALF, False), (0.0, A_FIFTH, False)],
        [GREEN, BLUE],
        over(0.2, BLUE, over(0.5, GREEN, BG)),
    ),
    # Two opaque quads at one depth: pass 2's EQUAL passes both, the last drawn stays.
    "opaque-tie": ([(0.0, 0.5, True), (0.0, 0.5, False)], [RED, GREEN], GREEN),
    # Nothing opaque, one back face behind the background only.
    "single-back": ([(0.0, A_HALF, False)], [GREEN], over(0.5, GREEN, BG)),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_hand_built_jax(name):
    specs, colors, expected = CASES[name]
    image = _jax_image(_view(), _quads(specs), np.array(colors))
    # float64 sums of a few products: 1e-12 is rounding.
    np.testing.assert_allclose(_centre_pixel(image)[:3], expected, atol=1e-12)
    opaque = any(u == 0.5 for _, u, _ in specs)
    alpha = 1.0 if opaque else 1 - np.prod([1 - (1 - abs(2 * u - 1)) for _, u, _ in specs])
    if name == "front-near-first":
        alpha = 0.5
    np.testing.assert_allclose(_centre_pixel(image)[3], alpha, atol=1e-12)


@pytest.mark.parametrize("name", sorted(CASES))
def test_hand_built_gl(gl, name):
    from hairjax.gl._patches import render_patches_gl

    specs, colors, expected = CASES[name]
    view = _view()
    image = render_patches_gl(gl, view, _quads(specs), np.array(colors), BG)
    # float32 colour buffer and blending: 1e-6 is a few float32 ulps of values ≤ 1.
    np.testing.assert_allclose(_centre_pixel(image)[:3], expected, atol=1e-6)
    # Every pixel, not only the centre; no pixel centre lies within 1e-2 px of an edge, so
    # float32 cannot change which fragments exist.
    patches = _quads(specs)
    xy, _ = view.project(patches.vertices)
    t = patches.triangles
    edges = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    assert not _near_segments(xy[edges[:, 0]], xy[edges[:, 1]], 1e-2, view.width, view.height).any()
    np.testing.assert_allclose(image, _jax_image(view, _quads(specs), np.array(colors)), atol=1e-6)


def test_alpha_threshold():
    # The profile: 1 on the core |u − ½| ≤ c/2, 0 at the edges, linear between.
    np.testing.assert_allclose(
        patch_alpha(np.array([0.0, 0.1, 0.3, 0.5, 0.7, 1.0]), 0.4),
        [0.0, 1 / 3, 1.0, 1.0, 1.0, 0.0],
        atol=1e-15,
    )
    assert np.all(patch_alpha(np.array([0.0, 0.5, 1.0]), 1.0) == 1.0)
    # a = 1 − 1e-3 is transparent (blended at its alpha), a = 1 opaque (written as is).
    view = _view()
    for u, opaque in [(0.5 - 0.5e-3, False), (0.5, True)]:
        patches = _quads([(0.0, u, True)])
        frags = patch_fragments(view, patches)
        assert np.all((frags.alpha >= 1 - PATCH_OPAQUE_EPS) == opaque)
        pixel = _centre_pixel(_jax_image(view, patches, np.array([RED])))
        expected = RED if opaque else over(1 - 1e-3, RED, BG)
        np.testing.assert_allclose(pixel[:3], expected, atol=1e-12)
    with pytest.raises(ValueError, match="opaque core"):
        patch_mesh(
            np.zeros((2, 3)), np.array([0, 2]), np.zeros((2, 3)), np.zeros((2, 3)), 1.0, 1.5, np.zeros(3)
        )
    with pytest.raises(ValueError, match="patch width"):
        patch_mesh(
            np.zeros((2, 3)), np.array([0, 2]), np.zeros((2, 3)), np.zeros((2, 3)), 0.0, 0.5, np.zeros(3)
        )
    for bad, message in [
        ((0, 1.0, 0.0), "strands across"),
        ((2, 1.5, 0.0), "strand alpha"),
        ((2, 1.0, -1.0), "tips"),
    ]:
        with pytest.raises(ValueError, match=message):
            patch_mesh(
                np.zeros((2, 3)),
                np.array([0, 2]),
                np.zeros((2, 3)),
                np.zeros((2, 3)),
                1.0,
                0.5,
                np.zeros(3),
                *bad,
            )


def _pcg_by_hand(x: int) -> int:
    """Jarzynski & Olano's pcg_hash (JCGT 2020) in Python integers mod 2³², written out
    apart from the code under test."""
    m = 0xFFFFFFFF
    state = (x * 747796405 + 2891336453) & m
    word = (((state >> ((state >> 28) + 4)) ^ state) * 277803737) & m
    return (word >> 22) ^ word


def test_strand_texture():
    """docs/model.md §18's texture, checked against the formula evaluated by hand."""
    # The hash: pcg(k + pcg(patch)) mod 2³², including patch ids past 2¹⁶ and the wrap.
    for patch, k in [(0, 0), (3, 5), (70000, 11), (2**31 + 7, 2**32 - 1)]:
        assert int(strand_hash(np.array([patch]), np.array([k]))[0]) == _pcg_by_hand(
            (k + _pcg_by_hand(patch)) & 0xFFFFFFFF
        )
    n, c, m, tips = 6, 0.4, 0.3, 0.5
    patch = 17
    # Across u: strand k's profile between k/n and (k + 1)/n, 0 at both ends, its peak α_k on
    # the core; α_k = 1 for q = ⌊h/2²⁴⌋/256 ≥ 1 − PATCH_OPAQUE_STRANDS, else m + (1 − m)q/(1 − share).
    for k in range(n):
        h = _pcg_by_hand((k + _pcg_by_hand(patch)) & 0xFFFFFFFF)
        q = (h >> 24) / 256
        rest = 1 - PATCH_OPAQUE_STRANDS
        peak = 1.0 if q >= rest else m + (1 - m) * q / rest
        length = 1 - tips * (h & 0xFFFF) / 65536
        u = (k + np.array([0.0, 0.15, 0.5, 0.85, 1.0])) / n
        # v = 0 (at the root): the strand is there; profile 0, ½, 1, ½, 0 at t = 0, .15, .5, .85, 1.
        a = patch_texture(u, np.zeros(5), np.full(5, patch), c, n, m, tips)
        np.testing.assert_allclose(a, peak * np.array([0.0, 0.5, 1.0, 0.5, 0.0]), atol=1e-12)
        # Along v: the strand ends at its length 1 − λ·g.
        a = patch_texture(
            np.full(2, (k + 0.5) / n),
            np.array([length - 1e-9, length + 1e-9]),
            np.full(2, patch),
            c,
            n,
            m,
            tips,
        )
        np.testing.assert_allclose(a, [peak, 0.0], atol=1e-12)
    # Over many patches, the share of opaque strands is PATCH_OPAQUE_STRANDS (binomial, 4σ),
    # and the others peak within [m, 1 − (1 − m)/128], well below the opaque threshold.
    patches = np.repeat(np.arange(4000), n)
    u = (np.tile(np.arange(n), 4000) + 0.5) / n
    peaks = patch_texture(u, np.zeros(u.size), patches, c, n, m, tips)
    opaque = peaks >= 1 - PATCH_OPAQUE_EPS
    sigma = np.sqrt(PATCH_OPAQUE_STRANDS * (1 - PATCH_OPAQUE_STRANDS) / u.size)
    assert abs(opaque.mean() - PATCH_OPAQUE_STRANDS) < 4 * sigma
    assert peaks[~opaque].min() >= m and peaks[~opaque].max() <= 1 - (1 - m) / 128 + 1e-12
    # n = 1, m = 1, λ = 0 is the single profile a(u) = p(u).
    u = np.linspace(-0.01, 1.01, 41)
    np.testing.assert_array_equal(patch_texture(u, np.ones(41), np.arange(41), c), patch_alpha(u, c))


def _pixel_view(size=16):
    """An orthographic view whose pixel coordinates are the world's (x, y), depth z: GL's
    float32 window coordinates of the vertices below are then exact."""
    e = np.eye(3)
    return View(
        origin=np.zeros(3),
        forward=e[2],
        right=e[0],
        up=-e[1],
        width=size,
        height=size,
        focal=1.0,
        cx=0.0,
        cy=0.0,
        perspective=False,
        near=-np.inf,
    )


def _triangles(corners, colors=None):
    """Opaque triangles (core 1) at depth 1 with pixel-space corners `[T, 3, 2]`."""
    corners = np.asarray(corners, float).reshape(-1, 2)
    vertices = np.c_[corners, np.ones(len(corners))]
    return Patches(
        vertices,
        np.arange(len(corners)).reshape(-1, 3),
        np.full(len(corners), 0.5),
        np.arange(len(corners)),
        1.0,
    )


def test_gl_rounds_vertices_to_1_256_px(gl):
    """GL decides coverage on vertices rounded to 1/2^RASTER_SUBPIXEL_BITS = 1/256 px (ties
    to even) with the top-left rule (y up), and interpolates attributes from the unrounded
    positions (docs/model.md §18): measured with the patch shader on llvmpipe, and the
    JAX rasteriser does the same."""
    from hairjax.gl._patches import render_patches_gl

    assert gl.info["GL_SUBPIXEL_BITS"] == RASTER_SUBPIXEL_BITS == 8
    view = _pixel_view()
    centre = 8.5  # pixel (8, 8)'s centre, x and y
    # Each edge through x (or y) = 8.5 + k/4096 px; the triangle lies on one side of it.
    # Rounded to 1/256 = 16/4096 px, the edge sits on the centre for |k| ≤ 8 (k = ±8 are
    # ties, rounded to even: onto the centre) and passes it for |k| ≥ 9. On the edge, the
    # centre is covered for a left or bottom edge (y down: GL's top-left rule with y up),
    # not for a right or top one.
    sides = {
        "right edge": (lambda e: [(0, 0), (e, 0), (e, 16)], lambda k: k >= 9),
        "left edge": (lambda e: [(e, 0), (16, 0), (e, 16)], lambda k: k <= 8),
        "bottom edge": (lambda e: [(0, e), (16, e), (8, 0)], lambda k: k >= -8),
        "top edge": (lambda e: [(0, e), (8, 16), (16, e)], lambda k: k <= -9),
    }
    for name, (corners, expected) in sides.items():
        for k in [-9, -8, 0, 8, 9]:
            patches = _triangles(corners(centre + k / 4096))
            gl_covered = render_patches_gl(gl, view, patches, np.ones((3, 3)), BG)[8, 8, 3] == 1.0
            jax_covered = 8 * 16 + 8 in patch_fragments(view, patches).pixel
            assert gl_covered == jax_covered == expected(k), (name, k, gl_covered, jax_covered)
    # Attributes: colours that are the vertices' own (x, y) interpolate to the pixel
    # centre's (x, y) from the unrounded vertices; from the rounded ones they would be off
    # by up to the rounding, ~1e-3 px here (the vertices lie 0.3–0.45 steps off the grid).
    corners = (
        np.array([(0.3, 0.2), (15.7, 1.1), (2.2, 15.6)])
        + np.array([(0.35, -0.3), (0.4, 0.45), (-0.45, 0.38)]) / 256
    )
    patches = _triangles(corners)
    colors = np.c_[corners, np.zeros(3)]
    image = render_patches_gl(gl, view, patches, colors, BG)
    frags = patch_fragments(view, patches)
    j, i = np.divmod(frags.pixel, 16)
    centres = np.stack([i + 0.5, j + 0.5], axis=1)
    # float32 interpolation of values ≤ 16: a few ulps, ~1e-5.
    np.testing.assert_allclose(image[j, i, :2], centres, atol=1e-5)
    np.testing.assert_allclose(_jax_image(view, patches, colors)[j, i, :2], centres, atol=1e-12)
    rounded = np.round(corners * 256) / 256

    def cross(a, b):
        return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]

    area = cross(rounded[1] - rounded[0], rounded[2] - rounded[0])
    lam0 = cross(rounded[1] - centres, rounded[2] - centres) / area
    lam1 = cross(rounded[2] - centres, rounded[0] - centres) / area
    from_rounded = np.stack([lam0, lam1, 1 - lam0 - lam1], axis=1) @ corners
    assert np.abs(from_rounded - image[j, i, :2]).max() > 1e-4  # the test tells the two apart


def test_texture_jax_matches_gl(gl):
    """Two textured quads (7 strands across, m = 0.3, λ = 0.4, patch ids 3 and 70000), one
    over the other: JAX and GL draw the same strands. Tolerance 1e-4: float32 u (~1e-6 at
    64 px) times the profile's slope n/(½ − c/2) = 23, and float32 blending."""
    from hairjax.gl._patches import render_patches_gl

    vertices, triangles = [], []
    for q, (z, dx) in enumerate([(0.0, -0.3), (0.2, 0.3)]):
        vertices += [(-1.1 + dx, -1.2, z), (0.9 + dx, -1.2, z), (0.9 + dx, 1.1, z), (-1.1 + dx, 1.1, z)]
        triangles += [(4 * q, 4 * q + 1, 4 * q + 2), (4 * q, 4 * q + 2, 4 * q + 3)]
    patches = Patches(
        np.array(vertices),
        np.array(triangles),
        np.tile([0.0, 1.0, 1.0, 0.0], 2),
        np.repeat([0, 1], 4),
        0.4,
        np.tile([1.0, 1.0, 0.0, 0.0], 2),
        np.repeat([3, 70000], 4),
        7,
        0.3,
        0.4,
    )
    view = _view(64)
    colors = np.array([[1.0, 0.2, 0.1], [0.1, 0.8, 0.3]])
    frags = patch_fragments(view, patches)
    opaque = frags.alpha >= 1 - PATCH_OPAQUE_EPS
    # The texture is at work: opaque strands, semi-transparent ones and gaps between them.
    assert opaque.any() and ((frags.alpha > 0) & ~opaque).any() and (frags.alpha == 0).any()
    gl_image = render_patches_gl(gl, view, patches, colors, BG)
    np.testing.assert_allclose(gl_image, _jax_image(view, patches, colors), atol=1e-4)


def _strand_patches(width=0.3, core=0.4):
    """A small tuft: 24 seeded curved strands on a unit sphere's front, 5 points each."""
    rng = np.random.default_rng(7)
    strands = []
    for _ in range(24):
        root = rng.normal(size=3) * [0.6, 0.6, 0.2] + [0, 0, 0.8]
        root /= np.linalg.norm(root)
        bend = rng.normal(size=3) * 0.15
        s = np.linspace(0, 1, 5)[:, None]
        strands.append(root * (1 + 0.5 * s) + bend * s**2 + [0, -0.3, 0] * s)
    points = np.concatenate(strands)
    offsets = np.arange(0, 121, 5)
    tangent = tangents(points, offsets)
    centre = hair_centre(points, offsets)
    normal = strand_normals(points, tangent, centre)
    return patch_mesh(points, offsets, tangent, normal, width, core, centre), points, normal


def test_front_faces_point_outward():
    # Narrow ribbons: a wide one folds where N turns fast between points (a quad's two
    # triangles then bend apart, and one may face inward; docs/model.md §18).
    patches, points, normal = _strand_patches(width=0.05)
    v = patches.vertices
    t = patches.triangles
    n = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])
    mid = v[t].mean(axis=1)
    # The right-hand-rule normal agrees with the strand normal N (away from the centre).
    assert np.all(np.sum(n * normal[patches.point[t]].mean(axis=1), axis=1) > 0)
    # Seen from +z (outside the tuft), the fragments of outward faces are front faces: the
    # screen-area rule agrees with n·(eye − P) > 0.
    view = camera_view(Camera(eye=(0.0, 0.0, 5.0), fov=40.0, width=32, height=32))
    frags = patch_fragments(view, patches)
    facing = np.sum(n * (view.origin - mid), axis=1) > 0
    assert frags.pixel.size > 0
    np.testing.assert_array_equal(frags.front, facing[frags.draw])


# GL's window coordinates are float32: a vertex within this many px of a rounding boundary
# (k + ½)/256 may round to the other neighbour in GL. Its projection's float32 error is a
# few ulps of the coordinate (ulp(64) = 7.6e-6 px) amplified by the perspective division;
# 1e-4 px bounds it with margin.
WINDOW_F32 = 1e-4


def _rounding_mask(view, patches, frags):
    """Pixels where float32 may change which fragments exist or pass a test (docs/model.md
    §18): centres within 1/256 + WINDOW_F32 px of an edge that has a vertex within
    WINDOW_F32 px of a rounding boundary (GL may round it the other way, moving the edge
    by 1/256 px); fragments within 1e-4 of the opaque threshold; and pixels with
    two fragments whose depths differ by < 1e-5 of the depth range (the depth buffer's
    24 bits: 6e-8 of it)."""
    xy, depth = view.project(patches.vertices)
    scaled = xy * 2**RASTER_SUBPIXEL_BITS
    ambiguous = np.any(np.abs(scaled - np.floor(scaled) - 0.5) < WINDOW_F32 * 2**RASTER_SUBPIXEL_BITS, axis=1)
    t = patches.triangles
    edges = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    edges = edges[ambiguous[edges].any(axis=1)]
    mask = _near_segments(
        xy[edges[:, 0]], xy[edges[:, 1]], 2**-RASTER_SUBPIXEL_BITS + WINDOW_F32, view.width, view.height
    )
    # The profile before its clamp, (½ − |u − ½|)/(½ − c/2) (one strand across): float32 u
    # moves it by ~3e-6 here, so within 1e-4 of 1 − ε GL may call the fragment the other way.
    u = np.sum(frags.lam * patches.u[patches.triangles[frags.draw]], axis=1)
    raw = (0.5 - np.abs(u - 0.5)) / (0.5 - 0.5 * patches.core)
    mask[frags.pixel[np.abs(raw - (1 - PATCH_OPAQUE_EPS)) < 1e-4]] = True
    order = np.lexsort((frags.depth, frags.pixel))
    d, p = frags.depth[order], frags.pixel[order]
    tie = (p[1:] == p[:-1]) & (np.diff(d) < 1e-5 * 2 * depth.max())
    mask[p[1:][tie]] = True
    return mask


def test_jax_matches_gl(gl):
    """A 40² tuft of patches with seeded point colours: JAX's rasteriser rounds vertices as
    GL's does, so outside `_rounding_mask` every pixel agrees to 1e-4 (float32 colours,
    barycentrics and blending, ~1e-6; float32 u times the profile's slope 1/(½ − c/2) = 3.3).
    (Before the rounding was modelled this needed a first-order bound on its effect, and
    5 % of the covered pixels could exceed 1e-4.)"""
    from hairjax.gl._patches import render_patches_gl

    patches, points, _ = _strand_patches()
    view = camera_view(Camera(eye=(0.3, 0.2, 4.0), target=(0.0, -0.1, 0.8), fov=30.0, width=40, height=40))
    colors = np.random.default_rng(3).uniform(0.1, 1.0, size=(len(points), 3))
    jax_image = _jax_image(view, patches, colors)
    gl_image = render_patches_gl(gl, view, patches, colors, BG)
    frags = patch_fragments(view, patches)
    mask = _rounding_mask(view, patches, frags)
    assert np.any(frags.pixel[1:] == frags.pixel[:-1])  # the tuft overlaps itself: the passes have work
    covered = np.zeros(view.width * view.height, bool)
    covered[frags.pixel] = True
    assert covered.sum() > 100 and mask.sum() < 0.1 * covered.sum()
    diff = np.abs(gl_image - jax_image).max(axis=-1).ravel()
    bad = np.flatnonzero((diff > 1e-4) & ~mask)
    assert bad.size == 0, (bad, diff[bad])


# --------------------------------------------------------------------------- scenes

EXAMPLE = EXAMPLES / "patches.toml"


def _example(size=96):
    """The example scene (a head under three layers of textured patches) at size²."""
    scene = hj.load_scene(EXAMPLE)
    return scene.replace(camera=dataclasses.replace(scene.camera, width=size, height=size))


def test_scene_file_keys(tmp_path):
    scene = hj.load_scene(EXAMPLE)
    assert scene.patches == PatchGeometry(width=0.4, opaque_core=0.4, strands=10, strand_alpha=0.3, tips=0.3)
    assert scene.occluder is not None and scene.occluder.kind == "sphere"  # the head
    base = EXAMPLE.read_text()
    for old, new, message in [
        ('geometry = "patches"\n', "", "applies only to geometry = 'patches'"),
        ("patch_width = 0.4 ", "patch_width = 0.0 ", "patch_width"),
        ("patch_width = 0.4    # world units\n", "", "patch_width .* is required"),
        ("opaque_core = 0.4", "opaque_core = 1.5", "opaque_core"),
        ("patch_strands = 10", "patch_strands = 0", "patch_strands"),
        ("patch_strands = 10", "patch_strands = 2.5", "patch_strands"),
        ("patch_strand_alpha = 0.3", "patch_strand_alpha = 1.2", "patch_strand_alpha"),
        ("patch_strand_tips = 0.3", "patch_strand_tips = -0.1", "patch_strand_tips"),
        ('geometry = "patches"', 'geometry = "quads"', "geometry"),
    ]:
        path = tmp_path / "bad.toml"
        assert old in base
        path.write_text(base.replace(old, new))
        with pytest.raises(SceneError, match=message):
            hj.load_scene(path)
    for key in ("patch_strands = 10\n", "patch_strand_alpha = 0.3", "patch_strand_tips = 0.3"):
        path.write_text(base.replace('geometry = "patches"\n', "").replace("patch_width = 0.4 ", "#"))
        path.write_text(path.read_text().replace("opaque_core = 0.4", "#"))
        with pytest.raises(SceneError, match="applies only to geometry = 'patches'"):
            hj.load_scene(path)
        assert key.split()[0] in path.read_text()


def test_four_passes_over_the_head():
    """The head drawn first (slide 16): its depth primes Z, its colour is the backdrop, by
    hand as CASES: a transparent quad in front blends over it, one behind it is hidden, an
    opaque quad in front replaces it."""
    view = _view()
    centre = (view.height // 2) * view.width + view.width // 2
    head_rgb = np.array([0.9, 0.7, 0.5])
    head_colors = np.tile(head_rgb, (view.width * view.height, 1))
    for specs, colors, head_z, expected in [
        ([(0.5, A_HALF, True)], [GREEN], 4.0, over(0.5, GREEN, head_rgb)),  # D = 3.5 < 4
        ([(0.5, A_HALF, True)], [GREEN], 3.0, head_rgb),  # the quad behind the head
        ([(0.5, A_HALF, False)], [GREEN], 3.0, head_rgb),  # a back face behind it (pass 3)
        ([(0.5, 0.5, True)], [RED], 4.0, RED),  # an opaque quad in front
        ([(0.0, 0.5, True), (0.5, A_HALF, True)], [RED, GREEN], 4.2, over(0.5, GREEN, RED)),
        ([(0.0, 0.5, True), (0.5, A_HALF, True)], [RED, GREEN], 3.8, over(0.5, GREEN, head_rgb)),
    ]:
        patches = _quads(specs)
        frags = patch_fragments(view, patches)
        head = np.full(view.width * view.height, np.inf)
        head[centre] = head_z
        weights = four_pass_weights(frags, view.width * view.height, head)
        image = composite_patches(
            frags,
            weights,
            jnp.asarray(colors),
            jnp.asarray(BG),
            view.height,
            view.width,
            jnp.asarray(head_colors),
        )
        pixel = np.asarray(image).reshape(-1, 4)[centre]
        # float64 sums of a few products: 1e-12 is rounding.
        np.testing.assert_allclose(pixel, [*expected, 1.0], atol=1e-12)


def test_scene_jax_matches_gl(gl):
    """The example at 96² through `render` and `render_gl` (the same patches, the same JAX
    point colours and head light): the share of pixels where they differ by more than 1e-4
    (RGB, largest channel) is at most 0.1 % — measured 0 at 96², 128² and 256², the largest
    difference 5e-5 (the alpha channel: 0.09 % of the pixels, up to 2e-4, float32 u times
    the strand texture's slope n/(½ − c/2) = 33 on strands about a pixel wide)."""
    from hairjax.gl import render_gl

    scene = _example()
    jax_image = np.asarray(hj.render(scene))
    gl_image = render_gl(scene).image
    diff = np.abs(jax_image - gl_image)[..., :3].max(axis=-1)
    assert np.mean(diff > 1e-4) <= 1e-3, (np.mean(diff > 1e-4), diff.max())
    # The scene does what the example promises: the head shows (opaque, its colour), the
    # patches cover it in layers, their texture leaves opaque and see-through strands.
    view = camera_view(scene.camera)
    frags = patch_fragments(view, scene_patches(scene))
    opaque = frags.alpha >= 1 - PATCH_OPAQUE_EPS
    assert opaque.any() and ((frags.alpha > 0) & ~opaque).any()
    assert np.bincount(frags.pixel).max() >= 6  # layers over layers
    head, _, _ = hj._geometry._occluder.occluder_hits(view, scene.occluder)
    assert np.mean(np.isfinite(head) & (jax_image[..., 3].ravel() == 1.0)) > 0.2


def test_patch_image_differentiable():
    """The weights are geometry; the image is linear in the point colours, so a gradient in
    a shading parameter flows (float64 central difference, ε = 1e-6: error ~ε² + rounding)."""
    import equinox as eqx
    import jax

    scene = _example()
    p = scene.params

    def total(s):
        return jnp.sum(hj.render(scene, eqx.tree_at(lambda q: q.kd, p, s * p.kd))[..., :3])

    grad = jax.grad(total)(1.0)
    eps = 1e-6
    fd = (total(1.0 + eps) - total(1.0 - eps)) / (2 * eps)
    # Linear in kd (the head's colour does not depend on it): the central difference is
    # exact but for rounding (~1e-16/ε relative).
    np.testing.assert_allclose(float(grad), float(fd), rtol=1e-7)
    assert float(grad) > 0


def test_strand_scene_untouched():
    """A strand scene does no patch work: `render` is the staged path, bit for bit."""
    from hairjax import geometry_stage, shading_stage

    scene = _example().replace(patches=None)
    np.testing.assert_array_equal(
        np.asarray(hj.render(scene)), np.asarray(shading_stage(geometry_stage(scene), scene.params))
    )


def test_other_entry_points():
    """`render_profiled` draws the patches too; `fit` refuses them rather than fitting
    the ribbons' image."""
    from hairjax import render_profiled

    scene = _example()
    image, timings = render_profiled(scene)
    np.testing.assert_array_equal(np.asarray(image), np.asarray(hj.render(scene)))
    assert "patches (four passes)" in timings
    with pytest.raises(hj.FitError, match="hair-patch"):
        hj.fit(scene, np.zeros((96, 96, 4)))
