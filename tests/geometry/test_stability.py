"""Numerical stability of the geometry stage (the shared part and the other
stages: tests/stability_helpers.py): projection, rasteriser, ordering, shadows, occluder
and set-up on extreme and degenerate inputs, and the guards that keep them finite.

| case                            | test_…                                  | scene: own assertions          |
|---------------------------------|-----------------------------------------|--------------------------------|
| width 0.25 … 8 px               | widths_quarter_and_eight_pixels         | mixed: a·coverage by hand      |
| Ω in the thousands              | omega_in_the_thousands                  | stack: Ω = Σ others' a ≈ 1100  |
| point light at a strand point   | point_light_at_a_strand_point           | ambient there; Ω = 0 off map   |
| point light at the hair centre  | point_light_at_the_hairs_centre         | Ω = 0 for the unseen points    |
| zero-length, repeated points    | zero_length_segments_and_repeated_points| ambient·c exactly, not drawn   |
| all points at one depth         | all_points_at_one_depth                 | flat: Ω = 0 exactly (both Ω)   |
| camera inside the hair          | camera_inside_the_hair                  | inside                         |
| coordinates ~1e4 and ~1e-4      | coordinates_around_1e4_and_1e_minus_4   | = unscaled image and gradients |

Found here: (1) a point light at the hair's bounding-box centre raised a RuntimeWarning
(texel cast of ~1e300): fixed in _shadows.light_fragments. (2) A camera up of length < 1e-9
(or within 1e-9 rad of forward, which Camera accepts) turned the image by 90°: fixed in
_projection._basis.

| guard (file: function)                          | test_guard_… (or test_… in full)            |
|-------------------------------------------------|---------------------------------------------|
| _setup: to_light/unit_rows at a point light     | test_point_light_at_a_strand_point          |
| _occluder: sphere_hits sqrt(where(disc ≥ 0))    | sphere_rays_that_miss_and_an_eye_inside     |
| _occluder: sphere_hits far root (eye inside)    | sphere_rays_that_miss_and_an_eye_inside     |
| _occluder: sphere_hits _unit(point − centre)    | unreachable: hits at the radius, misses out |
| _setup: _prepare Lambert clip (max(N·L, 0))     | sphere_rays_that_miss_and_an_eye_inside     |
| _occluder: vertex_normals/_unit, zero sum       | test_occluder::…degenerate_triangles_…      |
| _occluder: mesh_hits zero-area projections      | test_occluder::…degenerate_triangles_…      |
| _occluder: _near_segments zero-length edge      | test_occluder::…degenerate_triangles_…      |
| _occluder: occluder_visibility off the map      | test_occluder::…degenerate_triangles_…      |
| _shadows: map_margin initial=1.0                | map_margin_without_strands                  |
| _shadows: light_frame span fallback             | light_sees_all_points_at_one_depth          |
| _shadows: light_frame, no point seen            | no_point_in_front_of_a_point_light          |
| _shadows: light_fragments texel clip (new)     | test_point_light_at_the_hairs_centre        |
| _shadows: OpacityMaps.setup slice clip [0, N]  | fragment_below_the_nearest_plane (rounding) |
| _shadows: ExactShadows.setup key clip, valid   | no_point_in_front_of_a_point_light          |
| _shadows: point_planes clips                    | plane_clamps                                |
| _shadows: point_opacity maximum/where           | points_outside_the_light_map                |
| _shadows: exact_opacity, no fragments           | exact_shadows_without_fragments             |
| _projection: View.project where(depth > near)   | projection_at_and_behind_the_eye            |
| _projection: _basis fallback to x               | basis_when_up_is_parallel_to_forward        |
| _projection: _basis fallback to z               | unreachable: Camera rejects up ∥ forward,   |
|                                                 | and a light's forward ∥ y is not ∥ x        |
| _projection: light_view extent fallback         | light_sees_all_points_at_one_spot           |
| _projection: light_view axis fallback, near max | no_point_in_front_of_a_point_light          |
| _projection: light_view tan clamps              | point_light_field_of_view_clamps            |
| _projection: light_view, none in front          | no_point_in_front_of_a_point_light          |
| _ordering: bin_index span fallback, minimum     | depth_bins_of_one_depth_and_…_subnormal_span|
| _raster: rasterize zero-length columns, empty   | rasteriser_zero_length_and_empty_input      |
| _raster: the raster kernel's za == zb           | constant_depth_fragments_keep_z             |

The modules are hairjax/_geometry's (test_occluder:: is tests/geometry/test_occluder.py).
The GL side of these cases (the `gl` backend) reaches the GLSL guards listed in
tests/gl/test_stability.py.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from stability_helpers import (
    BACKENDS,
    COINCIDENT,
    DEFAULT,
    FUR,
    LIGHT_POINT,
    REPEATED,
    SINGLE,
    SIZE,
    THIN_Y,
    WIDE_Y,
    camera,
    channel_bound,
    check,
    pixel_of,
    precision,
    runner,
    runner_scene,
    unit_roundoff,
)

import hairjax as hj

# --- the cases -----------------------------------------------------------------------------


def coverage_by_hand(d: float, w: float) -> float:
    """docs/model.md §5's cross-ribbon coverage, written out independently of _raster."""
    return min(max(min(d + 0.5, w / 2) - max(d - 0.5, -w / 2), 0.0), 1.0)


@pytest.mark.parametrize("backend", BACKENDS)
def test_widths_quarter_and_eight_pixels(request, backend):
    """Ribbons of width 0.25 and 8 px: the alpha channel across each equals a·coverage of
    docs/model.md §5 by hand (the thin and wide strands lie apart from the rest)."""
    image, _ = check(backend, request, "mixed")
    alpha = image[..., 3]
    a = 0.5
    # Coverage is 1-Lipschitz in d, and d carries a few ulps of the raster coordinate
    # (the projection's and the kernel's rounding): 16 ulps of SIZE.
    tol = 16 * unit_roundoff(np.float64 if backend == "float64" else np.float32) * SIZE
    col = SIZE // 2
    for y_world, width, rows in ((THIN_Y, 0.25, range(2, 6)), (WIDE_Y, 8.0, range(24, 31))):
        _, y = pixel_of((0.0, y_world, 0.0))
        for row in rows:
            expected = a * coverage_by_hand(abs(row + 0.5 - y), width)
            assert abs(alpha[row, col] - expected) <= tol, (width, row, alpha[row, col], expected)
    # The fur ball stays clear of those rows (the premise of the check above).
    fur = runner_scene("mixed").strands.points[: runner_scene("mixed").strands.offsets[FUR]]
    fur_rows = np.array([pixel_of(p)[1] for p in fur])
    assert fur_rows.min() > 6 and fur_rows.max() < 23
    # The thin ribbon never covers more than its width.
    assert alpha[2:6].max() <= 0.25 * a + tol


@pytest.mark.parametrize("backend", BACKENDS)
def test_zero_length_segments_and_repeated_points(request, backend):
    """Repeated points (zero-length segments, zero one-sided tangent), three coincident
    points and a one-point strand: they draw nothing and reflect ambient light only."""
    image, res = check(backend, request, "mixed")
    s = runner_scene("mixed").strands
    for strand in (COINCIDENT, SINGLE):
        x, y = pixel_of(s.points[s.offsets[strand]])
        assert image[int(y), int(x), 3] == 0.0  # nothing else lies there
    if backend != "gl":
        zero_tangent = [s.offsets[REPEATED], *range(s.offsets[COINCIDENT], s.offsets[SINGLE + 1])]
        # ambient·c exactly, in the run's precision: diffuse and specular are exact zeros.
        dtype = res.colors.dtype
        np.testing.assert_array_equal(
            res.colors[zero_tangent], dtype.type(DEFAULT["ambient"]) * s.color[zero_tangent].astype(dtype)
        )


@pytest.mark.parametrize("backend", BACKENDS)
def test_omega_in_the_thousands(request, backend):
    """1200 stacked strands: Ω at the farthest strand's middle point is the sum of all the
    other opacities (each ribbon covers its whole 3 × 3 box, docs/model.md §7), ~1100; each
    pixel on the line composites 1200 fragments and is opaque."""
    from hairjax.gl import render_gl

    image, res = check(backend, request, "stack")
    s = runner_scene("stack").strands
    # Strand 0 is the farthest from the light (z = −0.5); the last two draw nothing.
    expected = s.alpha[1:-2].sum()
    assert expected > 1000
    if backend == "gl":
        with precision("float64"):
            omega = render_gl(runner_scene("stack")).omega.astype(np.float64)
        u = unit_roundoff(np.float32)
    else:
        omega, u = res.omega, unit_roundoff(np.dtype(backend))
    # A sum of n = 1200 terms in (0, 1]: ≤ n·u relative rounding, twice that with the
    # 3 × 3 average and the plane interpolation.
    assert abs(omega[1] - expected) <= 2 * len(s.alpha) * u * expected
    assert image[SIZE // 2, SIZE // 2, 3] == 1.0


@pytest.mark.parametrize("backend", BACKENDS)
def test_point_light_at_a_strand_point(request, backend):
    """L = 0 at the point under the light (_unit's guard): ambient light only there; the
    points behind the light's near plane or beyond its ±80° map get Ω = 0."""
    from hairjax._geometry._shadows import light_frame
    from hairjax.gl import render_gl

    image, res = check(backend, request, "point_light")
    scene = runner_scene("point_light")
    s = scene.strands
    frame = light_frame(s.points, s.segments(), s.width, scene.light, SIZE)
    inside = np.all((frame.xy >= 0) & (frame.xy < SIZE), axis=1)
    unlit = ~frame.seen | ~inside
    assert unlit[LIGHT_POINT] and (~frame.seen).sum() > 1 and (frame.seen & ~inside).any()
    if backend == "gl":
        with precision("float64"):
            omega = render_gl(scene).omega
    else:
        omega = res.omega
        np.testing.assert_array_equal(
            res.colors[LIGHT_POINT], np.full(3, DEFAULT["ambient"], res.colors.dtype)
        )
    np.testing.assert_array_equal(omega[unlit], 0.0)


@pytest.mark.parametrize("backend", BACKENDS)
def test_point_light_at_the_hairs_centre(request, backend):
    """The light at the bounding-box centre (light_view's axis fallback, near ≈ 1e-303):
    the points at or above the light's level are unseen and get Ω = 0; the rest are
    shadowed as usual (some Ω > 0)."""
    from hairjax._geometry._shadows import light_frame
    from hairjax.gl import render_gl

    _, res = check(backend, request, "centre_light")
    scene = runner_scene("centre_light")
    s = scene.strands
    frame = light_frame(s.points, s.segments(), s.width, scene.light, SIZE)
    np.testing.assert_array_equal(frame.view.forward, [0.0, -1.0, 0.0])
    if backend == "gl":
        with precision("float64"):
            omega = render_gl(scene).omega
    else:
        omega = res.omega
    assert (~frame.seen).sum() > 10 and omega.max() > 0
    np.testing.assert_array_equal(omega[~frame.seen], 0.0)


@pytest.mark.parametrize("backend", BACKENDS)
def test_all_points_at_one_depth(request, backend):
    """Every point at one depth from the camera (one visibility bin) and from the light
    (span fallback, constant-depth fragments keep z exactly): nothing is strictly nearer
    the light than anything, so Ω = 0 exactly, with `exact` and with opacity maps."""
    from hairjax.gl import render_gl

    _, res = check(backend, request, "flat")
    maps = runner_scene("flat").replace(shadows=hj.Shadows("opacity-maps", 4, SIZE))
    if backend == "gl":
        with precision("float64"):
            omegas = [render_gl(runner_scene("flat")).omega, render_gl(maps).omega]
    else:
        with precision(backend):
            scene = runner("flat", backend).scene
            omegas = [
                res.omega,
                np.asarray(
                    hj.geometry_stage(scene.replace(shadows=hj.Shadows("opacity-maps", 4, SIZE))).omega
                ),
            ]
    for omega in omegas:
        np.testing.assert_array_equal(omega, 0.0)


@pytest.mark.parametrize("backend", BACKENDS)
def test_camera_inside_the_hair(request, backend):
    """The eye inside the fur ball: points behind it and within the near plane (their
    segments are not drawn; the projection's guard keeps their coordinates finite)."""
    check(backend, request, "inside")
    cam = runner_scene("inside").camera
    pts = runner_scene("inside").strands.points
    forward = np.subtract(cam.target, cam.eye) / np.linalg.norm(np.subtract(cam.target, cam.eye))
    depth = (pts - cam.eye) @ forward
    assert (depth < 0).sum() > 50 and ((depth > 0) & (depth <= cam.near * 100)).any()


def assert_same_setup(a, b, u: float):
    """Two geometry set-ups equal up to rounding. Integer and boolean arrays (which pixels,
    segments, texels) exactly; floats to 1000u: t = s/L divides a few ulps of coordinates
    up to ~10² px by screen lengths down to ~1 px; directions and coverage need far less."""
    for x, y in ((a, b), (a.shadow, b.shadow)):
        for field in dataclasses.fields(x):
            p, q = getattr(x, field.name), getattr(y, field.name)
            if not isinstance(p, np.ndarray):
                continue
            assert p.shape == q.shape, field.name
            if p.dtype.kind in "biu":
                np.testing.assert_array_equal(p, q, err_msg=field.name)
            else:
                np.testing.assert_allclose(p, q, rtol=0, atol=1000 * u, err_msg=field.name)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("scale", [1e-4, 1e4])
def test_coordinates_around_1e4_and_1e_minus_4(request, backend, scale):
    """The point-light scene scaled by 10⁻⁴ and 10⁴ (scene units of 100 µm … 10 km): the
    model is scale-free, so the renders equal the unscaled scene's.

    JAX: every scale-dependent step is the NumPy geometry set-up (projection, light view,
    near planes, tangents, the rasteriser's coordinates); the JAX stages see only its
    arrays and the shading parameters. The set-ups must agree to rounding (1000u), and the
    image and gradients (finite, within bounds: check_jax) with the unscaled scene's to
    1000·(p + 8)u of the maximum / of the largest gradient (b^p amplifies by p).
    GL projects the scaled coordinates in float32 itself: compared with JAX float64."""
    case = {1e-4: "point_light_1e-4", 1e4: "point_light_1e4"}[scale]
    image, res = check(backend, request, case)
    if backend == "gl":
        return
    with precision(backend):
        base = runner("point_light", backend)
        ref = base(base.scene.params, None, runner(case, backend).target)
        u = unit_roundoff(np.dtype(backend))
        assert_same_setup(
            hj.experimental.prepare(runner(case, backend).scene), hj.experimental.prepare(base.scene), u
        )
    rel = 1000 * (DEFAULT["shininess"] + 8) * u
    bound = channel_bound(base.scene, base.scene.params, np.dtype(backend)).max()
    assert np.abs(image - ref.image).max() <= rel * bound
    for got, want in zip(
        jax.tree_util.tree_leaves((res.g_params, res.g_alpha)),
        jax.tree_util.tree_leaves((ref.g_params, ref.g_alpha)),
    ):
        assert np.abs(np.asarray(got) - np.asarray(want)).max() <= rel * np.abs(np.asarray(want)).max()


# --- the guards ----------------------------------------------------------------------------
# One test per guard (the table in the module docstring): inputs that make it fire, and the
# guarded result checked against the model's value.


def test_guard_light_sees_all_points_at_one_depth():
    """_shadows.light_frame's span fallback: every point at one light depth gives span 1
    (any positive spacing: nothing is strictly nearer than anything, Ω = 0, asserted on
    both renderers in test_all_points_at_one_depth)."""
    from hairjax._geometry._shadows import light_frame

    pts = np.array([[0.0, 0.0, 0.0], [1.0, 0.5, 0.0], [-0.5, 1.0, 0.0]])
    frame = light_frame(pts, np.array([[0, 1], [1, 2]]), np.ones(1), hj.Light(direction=(0.0, 0.0, -1.0)), 16)
    assert np.ptp(frame.depth) == 0.0 and frame.span == 1.0


def test_guard_no_point_in_front_of_a_point_light():
    """A point light at its hair's bounding-box centre, every point level with it:
    light_view looks down −y (axis fallback), near = 1e-3·max(0, 1e-300), the field of
    view falls back to ±80°; light_frame sees no point (zmin = 0, span 1); every point
    gets Ω = 0 (texel −1 for the maps, zero weights for `exact`)."""
    from hairjax._geometry._shadows import ShadowInputs, exact_opacity, light_frame, point_opacity

    pts = np.array([[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    segs = np.array([[0, 1]])
    light = hj.Light(kind="point", position=(0.0, 0.0, 0.0))
    frame = light_frame(pts, segs, np.ones(1), light, 16)
    np.testing.assert_array_equal(frame.view.forward, [0.0, -1.0, 0.0])
    assert frame.view.near == 1e-3 * 1e-300 and not frame.seen.any()
    assert (frame.zmin, frame.span) == (0.0, 1.0) and frame.drawable.size == 0
    # usable = 16 − 2·margin(width 1) = 12 texels over ±80°.
    assert frame.view.focal == pytest.approx(6 / np.tan(np.radians(80.0)), rel=1e-12)
    inputs = ShadowInputs(pts, segs, np.zeros(1, int), np.ones(1), light)
    maps = hj.Shadows("opacity-maps", 2, 16).setup(inputs)
    np.testing.assert_array_equal(maps.texel, -1)
    omega = point_opacity(
        jnp.ones((3, 16, 16)), jnp.asarray(maps.plane), jnp.asarray(maps.f), jnp.asarray(maps.texel)
    )
    np.testing.assert_array_equal(omega, 0.0)
    exact = hj.Shadows("exact", resolution=16).setup(inputs)
    np.testing.assert_array_equal(exact.weight, 0.0)
    np.testing.assert_array_equal(
        exact_opacity(jnp.zeros(0), jnp.zeros(0, bool), jnp.asarray(exact.index), jnp.asarray(exact.weight)),
        0.0,
    )


def test_guard_points_outside_the_light_map():
    """_shadows.point_opacity's maximum/where: texel −1 (a point outside the map) gets
    Ω = 0 exactly and passes no gradient to the maps; a point inside interpolates."""
    from hairjax._geometry._shadows import point_opacity

    maps = jnp.arange(2 * 4 * 4, dtype=float).reshape(2, 4, 4)
    plane, f, texel = jnp.asarray([0, 0]), jnp.asarray([0.25, 0.25]), jnp.asarray([-1, 5])
    np.testing.assert_array_equal(point_opacity(maps, plane, f, texel), [0.0, 0.75 * 5 + 0.25 * 21])
    grad = jax.grad(lambda m: point_opacity(m, plane, f, texel)[0])(maps)
    np.testing.assert_array_equal(grad, 0.0)


def test_guard_plane_clamps():
    """_shadows.point_planes: a point at D_N (u = N) takes plane N − 1 with f = 1, i.e.
    Ω̄(D_N); a point nearer than D₀ (behind a point light, u < 0) plane 0 with f = 0."""
    from hairjax._geometry._projection import View
    from hairjax._geometry._shadows import LightFrame, point_planes

    view = View(
        origin=np.zeros(3),
        forward=np.array([0.0, 0.0, -1.0]),
        right=np.array([1.0, 0, 0]),
        up=np.array([0, 1.0, 0]),
        width=8,
        height=8,
        focal=1.0,
        cx=4.0,
        cy=4.0,
        perspective=False,
        near=-np.inf,
    )
    depth = np.array([1.0, 2.0, 3.0, 0.5])  # D₀ = 1, D_N = 3; the last one unseen
    frame = LightFrame(
        view, np.zeros((4, 2)), depth, np.array([True, True, True, False]), np.zeros(0, int), 1.0, 2.0
    )
    plane, f = point_planes(frame, 4)
    np.testing.assert_array_equal(plane, [0, 2, 3, 0])
    np.testing.assert_array_equal(f, [0.0, 0.0, 1.0, 0.0])


def test_guard_fragment_below_the_nearest_plane(monkeypatch):
    """OpacityMaps.setup's slice clip: a light-space fragment whose interpolated depth
    rounds below D₀ (u slightly < 0, only through rounding) goes to slice 0 (it counts for
    planes 1 … N), never to slice −1; one at D_N to slice N (beyond the last plane). The
    same in a render's plan, which sums the fragments on the host: its sums are the
    fragment plan's, none written outside the maps."""
    import dataclasses as dc

    import hairjax._geometry._shadows as shadows_mod
    import hairjax._geometry._shadows._frame as frame_mod

    real = frame_mod.rasterize_parts

    def nudged(*args):
        (frags,) = real(*args)  # one piece at this size
        depth = frags.depth.copy()
        depth[np.argmin(depth)] = np.nextafter(depth.min(), -np.inf)  # one ulp below D₀
        return [dc.replace(frags, depth=depth)]

    monkeypatch.setattr(frame_mod, "rasterize_parts", nudged)
    hair = hj.furball(6, 4, seed=1)
    segs = hair.segments()
    inputs = shadows_mod.ShadowInputs(
        hair.points, segs, hair.strand_of_point[segs[:, 0]], hair.width, hj.Light(direction=(0.3, -1.0, 0.2))
    )
    method = hj.Shadows("opacity-maps", 4, 16)
    setup = method.setup(inputs)
    slices = setup.frag_cell // 16**2
    assert slices.min() == 0 and slices.max() <= 4
    summed = method.setup(inputs._replace(opacity=hair.alpha)).slices
    expected = np.zeros_like(summed)  # the same products added in the same order (x64 here)
    np.add.at(expected, setup.frag_cell, hair.alpha[setup.frag_strand] * setup.frag_coverage)
    np.testing.assert_array_equal(summed, expected)


def test_guard_exact_shadows_without_fragments(request):
    """_shadows.exact_opacity's empty guard (and GL's empty-buffer guards): hair of
    one-point strands and zero-length segments draws no light-space fragment: Ω = 0 on
    both renderers; the image is the background."""
    hair = hj.Strands.from_list([[[0.0, 0.0, 0.0]], [[0.5, 0.2, 0.0], [0.5, 0.2, 0.0]]], alpha=0.7)
    scene = hj.Scene(
        hair, camera=camera(), shadows=hj.Shadows("exact", resolution=SIZE), background=(0.1, 0.2, 0.3)
    )
    geometry = hj.geometry_stage(scene)
    np.testing.assert_array_equal(geometry.omega, 0.0)
    image = np.asarray(hj.shading_stage(geometry, scene.params))
    np.testing.assert_array_equal(image, np.broadcast_to([0.1, 0.2, 0.3, 0.0], image.shape))
    request.getfixturevalue("gl")
    from hairjax.gl import render_gl

    result = render_gl(scene)
    np.testing.assert_array_equal(result.omega, 0.0)
    np.testing.assert_allclose(result.image, image, rtol=0, atol=1e-7)


def test_guard_map_margin_without_strands():
    """_shadows.map_margin's initial=1.0: no strands (an empty width array) → the margin
    of width 1: ⌈½ + ½⌉ + 1 = 2."""
    from hairjax._geometry._shadows import map_margin

    assert map_margin(np.zeros(0)) == 2 == map_margin(np.ones(1))


def test_guard_projection_at_and_behind_the_eye():
    """_projection.View.project: depth ≤ near (behind or at the eye) divides by near, so
    the coordinates stay finite (those segments are culled by the near plane); GLSL's
    project() has the same max(z, near), exercised by test_camera_inside_the_hair."""
    from hairjax._geometry._projection import camera_view

    cam = hj.Camera(eye=(0.0, 0.0, 0.0), target=(0.0, 0.0, -1.0), width=8, height=8, near=0.01)
    view = camera_view(cam)
    pts = np.array([[0.1, 0.2, 1.0], [0.1, 0.2, 0.0], [0.1, 0.2, -0.005]])  # depth −1, 0, 0.005
    xy, depth = view.project(pts)
    np.testing.assert_array_equal(depth, [-1.0, 0.0, 0.005])
    np.testing.assert_allclose(xy[:, 0], 4 + view.focal * 0.1 / 0.01, rtol=1e-15)
    np.testing.assert_allclose(xy[:, 1], 4 - view.focal * 0.2 / 0.01, rtol=1e-15)


def test_guard_basis_when_up_is_parallel_to_forward():
    """_projection._basis: a light straight down (forward ∥ the up hint y) takes x for its
    right; the result is orthonormal. A camera's up is validated against forward with a
    relative bound (1e-12); any up it accepts, however short or close to forward, gives
    docs/model.md §2's right = normalise(d × up) (up = (0, 1e-10, 0) used to fall back to
    another axis: the image turned by 90°)."""
    from hairjax._geometry._projection import _basis, camera_view, light_view

    view = light_view(hj.Light(direction=(0.0, -1.0, 0.0)), np.eye(3), 16, 2)
    basis = np.stack([view.right, view.up, view.forward])
    np.testing.assert_allclose(basis @ basis.T, np.eye(3), atol=1e-15)
    np.testing.assert_allclose(view.right, np.cross([0.0, -1.0, 0.0], [1.0, 0.0, 0.0]), atol=1e-15)
    reference = camera_view(hj.Camera(eye=(4.0, 0.0, 0.0), target=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0)))
    for up in ((0.0, 1e-10, 0.0), (1.0, 1e-10, 0.0)):
        view = camera_view(hj.Camera(eye=(4.0, 0.0, 0.0), target=(0.0, 0.0, 0.0), up=up))
        np.testing.assert_allclose(view.right, reference.right, atol=1e-6)
        np.testing.assert_allclose(view.up, reference.up, atol=1e-6)
    # The second fallback (z) needs forward ∥ the hint and ∥ x at once: unreachable.
    right, up = _basis(np.array([0.0, 1.0, 0.0]), np.array([0.0, 1.0, 0.0]))
    np.testing.assert_allclose(right, [0.0, 0.0, -1.0], atol=1e-15)


def test_guard_light_sees_all_points_at_one_spot():
    """_projection.light_view: hair along a directional light projects to one point of the
    light's view (extent 0): focal falls back to 1, every point lands on the map centre,
    no light-space fragment (zero-length ribbons), Ω = 0."""
    from hairjax._geometry._shadows import ShadowInputs

    pts = np.array([[0.2, 1.0, 0.3], [0.2, 0.0, 0.3], [0.2, -1.0, 0.3]])
    segs = np.array([[0, 1], [1, 2]])
    inputs = ShadowInputs(pts, segs, np.zeros(2, int), np.ones(1), hj.Light(direction=(0.0, -1.0, 0.0)))
    setup = hj.Shadows("exact", resolution=16).setup(inputs)
    assert setup.view.focal == 1.0 and setup.frag_strand.size == 0
    np.testing.assert_allclose(setup.view.project(pts)[0], 8.0, atol=1e-15)


def test_guard_point_light_field_of_view_clamps():
    """_projection.light_view's tan(half fov) clamps: points on the light's axis (lateral 0)
    take the 1e-6 floor (finite focal, all on the centre texel); a point 85° off the axis
    the ±80° cap, and it falls outside the map (Ω = 0, point_light case)."""
    from hairjax._geometry._projection import light_view

    light = hj.Light(kind="point", position=(0.0, 0.0, 2.0))
    on_axis = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
    view = light_view(light, on_axis, 16, 2)
    assert view.focal == pytest.approx(6 / 1e-6, rel=1e-12)
    np.testing.assert_allclose(view.project(on_axis)[0], 8.0, atol=1e-9)
    off = np.tan(np.radians(85.0))  # two points 85° off the axis, symmetric about it
    wide = np.array([[off, 0.0, 1.0], [-off, 0.0, 1.0], [0.0, 0.0, -1.0]])
    view = light_view(light, wide, 16, 2)
    np.testing.assert_array_equal(view.forward, [0.0, 0.0, -1.0])
    assert view.focal == pytest.approx(6 / np.tan(np.radians(80.0)), rel=1e-12)
    xy, _ = view.project(wide)
    assert np.all((xy[:2, 0] < 0) | (xy[:2, 0] >= 16))


def test_guard_depth_bins_of_one_depth_and_of_a_subnormal_span():
    """_ordering.bin_index: one depth puts everything in bin 0; with a subnormal span
    ε = span/2N rounds to 0, so D_max would land in bin N: the minimum keeps it in N − 1."""
    from hairjax._geometry._ordering import bin_index

    np.testing.assert_array_equal(bin_index(np.full(5, 3.25), 64), 0)
    span = 5e-322
    assert span + span / (2 * 256) == span  # the premise: ε is lost
    np.testing.assert_array_equal(bin_index(np.array([0.0, span]), 256), [0, 255])


def test_guard_rasteriser_zero_length_and_empty_input():
    """_raster.rasterize: zero-length segments get no columns (no fragments, no division
    by L = 0); no columns at all returns empty fragments of the working float type."""
    from hairjax._geometry._raster import rasterize

    p = np.array([[5.5, 5.5], [3.0, 4.0]])
    frags = rasterize(p, p, np.ones(2), np.ones(2), np.ones(2), 16, 16, True)
    assert frags.size == 0 and frags.coverage.dtype == np.float64
    none, empty = np.zeros((0, 2)), np.zeros(0)
    frags = rasterize(none, none, empty, empty, empty, 16, 16, False)
    assert frags.size == 0


@pytest.mark.parametrize("dtype", ["float64", "float32"])
def test_guard_constant_depth_fragments_keep_z(dtype):
    """The raster kernel's za == zb guard (_raster_loop's depth_at; GLSL fragment_depth's): a segment at one
    depth gives every fragment exactly that depth, although the perspective formula
    1/((1 − t)/z + t/z) rounds away from z (checked here, the guard's reason)."""
    from hairjax._geometry._raster import rasterize

    z = 1.469  # 1/(1/z) ≠ z in float64 and float32
    with precision(dtype):
        frags = rasterize(
            np.array([[1.2, 3.3]]),
            np.array([[14.7, 9.1]]),
            np.array([z]),
            np.array([z]),
            np.ones(1),
            16,
            16,
            True,
        )
        zz = frags.depth.dtype.type(z)
        assert frags.size > 10 and np.all(frags.depth == zz)
        t = frags.t
        assert np.any(1 / ((1 - t) / zz + t / zz) != zz)


def test_guard_sphere_rays_that_miss_and_an_eye_inside():
    """_render.sphere_hits: rays that miss (disc < 0) take sqrt(0), not NaN (NumPy would
    warn — an error here), and get depth ∞; with the eye inside, every ray takes the far
    root. Hits lie on the sphere; the Lambert term max(N·L, 0) is 0 on the unlit side."""
    from hairjax._geometry._occluder import sphere_hits
    from hairjax._geometry._projection import camera_view

    occ = hj.Occluder(center=(0.0, 0.0, 0.0), radius=0.5)
    for eye, hits in (((0.0, 0.0, 4.0), "some"), ((0.1, 0.0, 0.2), "all")):
        view = camera_view(hj.Camera(eye=eye, target=(0.0, 0.0, -1.0), width=16, height=16))
        depth, normal, point = sphere_hits(view, occ)
        hit = np.isfinite(depth)
        assert hit.all() if hits == "all" else 0 < hit.sum() < hit.size
        assert np.all(depth[hit] > 0)
        np.testing.assert_allclose(np.linalg.norm(point[hit], axis=1), 0.5, rtol=1e-12)
        np.testing.assert_allclose(normal[hit], point[hit] / 0.5, atol=1e-12)
    scene = hj.Scene(
        hj.Strands.from_list([[[2.0, 2.0, 0.0]]]),
        camera=hj.Camera(width=16, height=16),
        light=hj.Light(direction=(0.0, 0.0, 1.0)),
        occluder=occ,
        shadows=hj.Shadows("none"),
    )
    setup = hj.experimental.prepare(scene)
    assert setup.opaque.any() and np.all(setup.occluder_direct == 0.0)  # lit from behind
