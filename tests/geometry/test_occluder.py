"""The occluder (docs/model.md §9, §13): a mesh hides hair behind it, casts its shadow
(light-view depth test) and receives the hair's (τ = exp(−κΩ) at its surface); hand-made
cases, the κ-gradient, and JAX against GL."""

from __future__ import annotations

import jax
import numpy as np
import pytest
from helpers import DATA, EXAMPLES, central_difference, first_then_slow, shadow_method, unexplained_pixels

import hairjax as hj
from hairjax._disagreement import OCCLUDER_VERTEX_STEP, PIXEL_TOL
from hairjax._geometry._occluder import interpolation_bound
from hairjax._geometry._projection import camera_view
from hairjax._geometry._shadows import light_frame
from hairjax._shading import occluder_colors, point_colors


def quad(corners) -> hj.Occluder:
    """A planar quad a, b, c, d (counter-clockwise seen from its front) as two triangles."""
    return dict(vertices=np.asarray(corners, np.float64), triangles=[[0, 1, 2], [0, 2, 3]])


def hair_line(y=0.0, z=0.0, n=9):
    x = np.linspace(-1.0, 1.0, n)
    return np.stack([x, np.full(n, y), np.full(n, z)], axis=1)


def test_a_quad_in_front_hides_the_hair_behind_it():
    """Camera on +z; a quad at z = 0 over x < 0 faces it (normal +z, light along −z: N·L = 1).
    Left of centre the pixel is the quad's k·(ambient + light), nothing of the hair at
    z = −1 behind it; right of centre the hair shows; the quad behind the hair hides nothing."""
    hair = hj.Strands.from_list([hair_line(z=-1.0)], alpha=1.0)
    k = np.array([0.2, 0.4, 0.6])
    params = hj.ShadingParams(kd=0.5, ks=0.0, ambient=0.1)
    front = hj.Occluder(kind="mesh", color=k, **quad([[-3, -3, 0], [0, -3, 0], [0, 3, 0], [-3, 3, 0]]))
    base = dict(
        camera=hj.Camera(eye=(0, 0, 5), width=32, height=32),
        shadows=hj.Shadows("none"),
        light=hj.Light(direction=(0, 0, -1)),
        shading=hj.KajiyaKay(params),
    )
    img = np.asarray(hj.render(hj.Scene(hair, occluder=front, **base)))
    plain = np.asarray(hj.render(hj.Scene(hair, **base)))
    row = 16 if plain[16, 8, 3] > 0 else 15  # the hair's row (y = 0 is on a pixel edge)
    assert plain[row, 12, 3] > 0.4 and plain[row, 20, 3] > 0.4
    np.testing.assert_allclose(img[row, 12, :3], k * (0.1 + 1.0), rtol=1e-12)
    assert img[row, 12, 3] == 1.0
    np.testing.assert_array_equal(img[row, 20], plain[row, 20])
    behind = hj.Occluder(kind="mesh", color=k, **quad([[-3, -3, -2], [0, -3, -2], [0, 3, -2], [-3, 3, -2]]))
    img = np.asarray(hj.render(hj.Scene(hair, occluder=behind, **base)))
    assert np.abs(img[row, 12, :3] - k * 1.1).max() > 0.05  # the hair covers the quad


def test_a_quad_between_light_and_hair_leaves_only_ambient():
    """Light straight down; a quad at y = 1 over x < 0: the hair at y = 0 gets no direct
    light there (V = 0, colour ambient·c) and full light for x > 0 (V = 1)."""
    hair = hj.Strands.from_list([hair_line(n=9)], alpha=0.5)
    occ = hj.Occluder(kind="mesh", **quad([[-3, 1, 3], [0, 1, 3], [0, 1, -3], [-3, 1, -3]]))
    params = hj.ShadingParams(kd=0.5, ks=0.2, ambient=0.07, kappa=0.0)
    scene = hj.Scene(
        hair,
        camera=hj.Camera(eye=(0, 0, 5), width=32, height=32),
        light=hj.Light(direction=(0, -1, 0)),
        shading=hj.KajiyaKay(params),
        occluder=occ,
        shadows=hj.Shadows("opacity-maps", maps=4, resolution=32),
    )
    geom = hj.geometry_stage(scene)
    x = scene.strands.points[:, 0]
    # The point at x = 0 lies under the quad's edge: the map's texel there may go either way.
    clear = np.abs(x) > 0.2  # > 1 texel (the map spans ~2.5 units over 26 texels)
    np.testing.assert_array_equal(np.asarray(geom.light_visibility)[clear], np.where(x < 0, 0.0, 1.0)[clear])
    colors = np.asarray(point_colors(geom, params))
    np.testing.assert_allclose(colors[clear & (x < 0)], 0.07, rtol=1e-12)
    assert np.all(colors[clear & (x > 0)] > 0.07 + 0.4)  # Kd·sin(T, L) = 0.5 with T ⊥ L
    # No shadows, no shadow work: V is not computed.
    assert hj.geometry_stage(scene.replace(shadows=hj.Shadows("none"))).light_visibility is None


def slab_scene(method: str, kappa: float = 0.7):
    """Strands along x at y = 0.5, exactly one light texel apart in z and 2 texels wide,
    above a quad at y = 0 facing up; light straight down, camera below. A texel's column
    then holds ribbons whose coverages sum to the width, 2 (ribbons of integer width w at
    unit spacing cover each point w times), so under the middle Ω = 2a for any alignment,
    and the quad shows k·ambient + exp(−κ·2a)·k·light."""
    light = hj.Light(direction=(0.0, -1.0, 0.0))
    res, count = 32, 15

    def strands(spacing):
        z = (np.arange(count) - count // 2) * spacing
        return hj.Strands.from_list(
            [hair_line(y=0.5, z=zi, n=5) * [1.6, 1, 1] for zi in z], alpha=0.3, width=2.0
        )

    hair = strands(0.1)
    # Re-space the strands to one texel of the light's framing (set by the strands' x
    # extent, which the spacing leaves alone: one step reaches the fixed point).
    for _ in range(3):
        frame = light_frame(hair.points, hair.segments(), hair.width, light, res)
        spacing = 1.0 / frame.view.focal
        hair = strands(spacing)
    frame = light_frame(hair.points, hair.segments(), hair.width, light, res)
    assert abs(frame.view.focal * spacing - 1) < 1e-9
    occ = hj.Occluder(
        kind="mesh", color=(0.5, 0.6, 0.7), **quad([[-3, 0, 3], [3, 0, 3], [3, 0, -3], [-3, 0, -3]])
    )
    return hj.Scene(
        hair,
        camera=hj.Camera(eye=(0, -5, 0.0), up=(0, 0, -1), fov=20, width=16, height=16),
        light=light,
        occluder=occ,
        shadows=shadow_method(method, 4, res),
        shading=hj.KajiyaKay(hj.ShadingParams(kd=0.5, ks=0.1, ambient=0.05, kappa=kappa)),
    )


@pytest.mark.parametrize("method", ["opacity-maps", "exact"])
def test_the_occluder_under_a_slab_receives_exp_minus_kappa_omega(method):
    scene = slab_scene(method)
    img = np.asarray(hj.render(scene))
    geom = hj.geometry_stage(scene)
    centre = 8 * 16 + 8
    pixel = list(np.asarray(geom.occluder_pixel))
    q = pixel.index(centre)
    np.testing.assert_allclose(float(geom.occluder_omega[q]), 2 * 0.3, rtol=1e-9)
    k = np.array([0.5, 0.6, 0.7])
    np.testing.assert_allclose(img[8, 8, :3], k * 0.05 + np.exp(-0.7 * 0.6) * k, rtol=1e-9)
    # Without shadows the quad is fully lit: the shadow is the hair's.
    plain = np.asarray(hj.render(scene.replace(shadows=hj.Shadows("none"))))
    np.testing.assert_allclose(plain[8, 8, :3], k * 1.05, rtol=1e-12)


def test_kappa_gradient_through_the_receiving_occluder():
    """d/dκ of Σ image² (hair and the occluder beneath it) against central differences in
    float64 (ε = 1e-6·κ: truncation ~ε²·|f'''| ≪ the 1e-6 relative tolerance); and the
    occluder's own share is not zero."""
    scene = slab_scene("opacity-maps")

    def loss(kappa):
        p = scene.params
        return float(
            np.sum(
                np.asarray(
                    hj.render(
                        scene,
                        hj.ShadingParams(
                            kd=p.kd, ks=p.ks, shininess=p.shininess, ambient=p.ambient, kappa=kappa
                        ),
                    )
                )
                ** 2
            )
        )

    import jax.numpy as jnp

    def loss_jax(kappa):
        p = scene.params
        return jnp.sum(
            hj.render(
                scene,
                hj.ShadingParams(kd=p.kd, ks=p.ks, shininess=p.shininess, ambient=p.ambient, kappa=kappa),
            )
            ** 2
        )

    grad = float(jax.grad(loss_jax)(0.7))
    fd = central_difference(loss, 0.7, 1e-6 * 0.7)
    np.testing.assert_allclose(grad, fd, rtol=1e-6)
    # The quad's pixels alone, colour k·ambient + e^{−κΩ}·k (light 1, N·L = 1, V = 1):
    # d/dκ Σ colour² = Σ 2·colour·(−Ω e^{−κΩ} k), with each pixel's Ω.
    geom = hj.geometry_stage(scene)
    omega = np.asarray(geom.occluder_omega)[:, None]
    k = np.array([0.5, 0.6, 0.7])
    colour = k * 0.05 + np.exp(-0.7 * omega) * k
    by_hand = np.sum(2 * colour * -omega * np.exp(-0.7 * omega) * k)
    assert by_hand < -1.0
    occ_only = jax.grad(
        lambda kp: jnp.sum(
            occluder_colors(geom, hj.ShadingParams(kd=0.5, ks=0.1, ambient=0.05, kappa=kp)) ** 2
        )
    )(0.7)
    np.testing.assert_allclose(float(occ_only), by_hand, rtol=1e-9)


def gl_scenes():
    """Small scenes with an occluder: the two hand-made quads, the sphere scene and Sintel's
    head, each at ≤ 64² with small maps."""
    out = {"slab": slab_scene("opacity-maps"), "slab-exact": slab_scene("exact")}
    hair = hj.Strands.from_list([hair_line(n=9), hair_line(y=0.3, z=0.5, n=9)], alpha=0.5)
    out["quad-shadow"] = hj.Scene(
        hair,
        camera=hj.Camera(eye=(1, 2, 5), width=32, height=32),
        light=hj.Light(direction=(0.2, -1, 0.1)),
        shading=hj.KajiyaKay(hj.ShadingParams(kappa=0.5)),
        occluder=hj.Occluder(kind="mesh", **quad([[-3, 1, 3], [0, 1, 3], [0, 1, -3], [-3, 1, -3]])),
        shadows=hj.Shadows("opacity-maps", maps=4, resolution=32),
    )
    # A point light between two layers of hair: the upper layer lies behind the light's
    # near plane (V = 1 in both renderers: occluder_visibility's and the compute shader's
    # "unseen" branch); the quad under the light (x ≤ −0.3: a triangle reaching the light's
    # near plane would not be drawn, §13) shadows the lower layer where x ≤ −0.6.
    layers = hj.Strands.from_list(
        [hair_line(y=0.0, z=z, n=9) for z in (-0.2, 0.2)] + [hair_line(y=2.0, z=z, n=9) for z in (-0.2, 0.2)],
        alpha=0.5,
    )
    out["quad-point-light"] = hj.Scene(
        layers,
        camera=hj.Camera(eye=(0.5, 1.0, 5), target=(0, 1, 0), width=32, height=32),
        light=hj.Light(kind="point", position=(0.0, 1.0, 0.0)),
        shading=hj.KajiyaKay(hj.ShadingParams(kappa=0.5)),
        occluder=hj.Occluder(
            kind="mesh", **quad([[-3, 0.5, 3], [-0.3, 0.5, 3], [-0.3, 0.5, -3], [-3, 0.5, -3]])
        ),
        shadows=hj.Shadows("opacity-maps", maps=4, resolution=128),
    )  # bias 3 texels: 0.28 at z = 1
    small = hj.Camera(eye=(0.0, 0.6, 4.5), target=(0.0, 0.1, 0.0), width=64, height=64)
    sphere = hj.load_scene(EXAMPLES / "occluder.toml")  # with 600 of its 3,000 strands
    out["sphere"] = sphere.replace(
        camera=small,
        shadows=hj.Shadows("opacity-maps", 16, 64),
        strands=hj.scalp(strands=600, points=16, seed=4, length=0.6, radius=0.7, coverage=0.35, alpha=0.5),
    )
    if DATA.is_dir():
        sintel = hj.load_scene(EXAMPLES / "sintel.toml")
        out["sintel"] = sintel.replace(
            camera=hj.Camera(
                eye=sintel.camera.eye, target=sintel.camera.target, fov=sintel.camera.fov, width=64, height=64
            ),
            shadows=hj.Shadows("opacity-maps", 16, 128),
        )
        # A point light above the left shoulder: perspective light views, exact Ω.
        out["sintel-point"] = out["sintel"].replace(
            light=hj.Light(kind="point", position=(-30.0, 70.0, 40.0)),
            shadows=hj.Shadows("exact", resolution=128),
        )
    return out


SCENES = gl_scenes()


@pytest.mark.parametrize("name", first_then_slow(SCENES))
def test_gl_agrees_with_jax(gl, name):
    """With JAX's Ω and occluder light, GL's image equals JAX's to 1e-4 outside the camera
    band (hairjax/_disagreement: it holds the mesh's silhouette pixels and those where GL's
    vertex rounding may move the interpolated normal by > 1e-4, 16 % of Sintel at 64²,
    where most triangles are smaller than a pixel), and within that rounding's bound
    inside it. GL's own render differs only in renderer_band (which adds the points and
    occluder pixels whose V or Ω may differ). GL's own occluder light: V equal at all but
    ≤ 1 % of the strand points and of the occluder's pixels (a point within rounding of a
    texel edge or the bias may go either way: measured 0 on these scenes), Ω at the
    occluder's pixels within 1e-3 at all but ≤ 1 % (texel edges, as for strand points)."""
    from hairjax.gl import occluder_light, render_gl

    scene = SCENES[name]
    geom = hj.geometry_stage(scene)
    jax_image = np.asarray(hj.shading_stage(geom, scene.params))
    mine = occluder_light(scene, geom)
    result = render_gl(scene, omega=np.asarray(geom.omega), occluder=mine)
    bad, band = unexplained_pixels(scene, result.image, jax_image)
    assert bad.size == 0, f"{bad.size} pixels differ by > 1e-4 outside the band"
    # Inside sub-pixel triangles GL's normal follows llvmpipe's vertex rounding: the band
    # holds those pixels, and GL stays within the first-order bound there (+ 1e-4).
    diff = np.abs(result.image - jax_image).max(axis=-1).ravel()
    bound = interpolation_bound(camera_view(scene.camera), scene.occluder, scene.light, OCCLUDER_VERTEX_STEP)
    only_mesh = (np.asarray(geom.transmittance) == 1.0) & (np.asarray(geom.alpha_channel) == 1.0)
    assert np.all(diff[only_mesh] <= bound[only_mesh] + PIXEL_TOL)
    full = render_gl(scene)
    own = full.occluder
    # GL with its own Ω and V: differences lie in renderer_band (which adds the points and
    # occluder pixels whose V or Ω may differ, occluder_light_uncertainty) or are the mesh
    # interpolation above.
    diff = np.abs(full.image - jax_image).max(axis=-1).ravel()
    wide = hj.experimental.renderer_band(scene, float(jax_image[..., :3].max())).ravel()
    assert np.flatnonzero((diff > 1e-4) & ~wide).size == 0
    assert np.mean(own.visibility != mine.visibility) <= 0.01
    covered = np.asarray(geom.alpha_channel).reshape(jax_image.shape[:2]) == 1.0
    assert np.mean(own.surface_visibility[covered] != mine.surface_visibility[covered]) <= 0.01
    assert np.mean(np.abs(own.omega - mine.omega)[covered] > 1e-3) <= 0.01


def test_a_scene_without_occluder_does_no_occluder_work(monkeypatch):
    """No occluder: neither the rasterisation nor the shadow test runs, and the geometry
    carries no occluder fields (the image is the one of tests/test_render.py)."""
    from helpers import small_furball_scene

    from hairjax._geometry_stage import _lighting

    def forbidden(*args, **kwargs):
        raise AssertionError("occluder work in a scene without occluder")

    for name in ("occluder_hits", "occluder_light_view", "occluder_visibility"):
        monkeypatch.setattr(_lighting, name, forbidden)
    geom = hj.geometry_stage(small_furball_scene())
    assert geom.occluder_pixel is None and geom.light_visibility is None
    assert geom.occluder_omega is None


def test_mesh_occluder_in_a_scene_file(tmp_path):
    """[occluder] kind = "mesh" with a path relative to the file; keys of the other kind
    and missing files are refused, naming the key."""
    obj = tmp_path / "sub" / "quad.obj"
    obj.parent.mkdir()
    obj.write_text("v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3 4\n")
    head = '[hair]\nsource = "furball"\nstrands = 3\n[occluder]\nkind = "mesh"\n'
    path = tmp_path / "s.toml"
    path.write_text(head + 'path = "sub/quad.obj"\ncolor = [0.1, 0.2, 0.3]\n')
    occ = hj.load_scene(path).occluder
    assert occ.kind == "mesh" and occ.path == str(obj.resolve()) and occ.triangles.shape == (2, 3)
    assert occ == hj.Occluder(kind="mesh", path=str(obj.resolve()), color=(0.1, 0.2, 0.3))
    for extra, message in [
        ('path = "sub/quad.obj"\nradius = 2\n', "occluder.radius is only for kind = 'sphere'"),
        ("", "occluder.path is required"),
        ('path = "nope.obj"\n', "occluder.path file not found"),
        ('path = "sub/quad.ply"\n', "occluder.path must be a path to a .obj"),
    ]:
        path.write_text(head + extra)
        with pytest.raises(hj.SceneError, match=message):
            hj.load_scene(path)
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0\n")
    path.write_text(head + 'path = "bad.obj"\n')
    with pytest.raises(hj.SceneError, match=r"bad.obj:1: 'v' needs 3 coordinates"):
        hj.load_scene(path)


def test_guard_degenerate_triangles_and_a_mesh_behind_the_eye(gl):
    """_occluder: a zero-area triangle (collinear vertices) is drawn nowhere and its own
    vertices get the zero normal (vertex_normals/_unit, occluder_mesh.frag's guard), a
    zero-length edge is a point for silhouette_pixels (_near_segments); a mesh entirely
    behind the eye is drawn by neither renderer (drawable_triangles; GL's empty index
    buffer and depth_far without it); points outside the occluder's light map are lit."""
    from hairjax._geometry._occluder import mesh_hits, occluder_visibility, silhouette_pixels, vertex_normals
    from hairjax._geometry._projection import camera_view
    from hairjax.gl import render_gl

    flat = np.array([[-3, -3, 0], [0, -3, 0], [0, 3, 0], [-3, 3, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]], float)
    tris = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 4, 5]])
    n = vertex_normals(flat, tris)
    np.testing.assert_array_equal(n[4:], 0.0)
    np.testing.assert_allclose(n[:4], [[0, 0, 1]] * 4)
    hair = hj.Strands.from_list([hair_line(z=-1.0)], alpha=0.5)
    scene = hj.Scene(
        hair,
        camera=hj.Camera(eye=(0, 0, 5), width=16, height=16),
        light=hj.Light(direction=(0, 0, -1)),
        occluder=hj.Occluder(kind="mesh", vertices=flat, triangles=tris),
        shadows=hj.Shadows("opacity-maps", maps=4, resolution=16),
    )
    view = camera_view(scene.camera)
    depth, _, _ = mesh_hits(view, flat, tris[2:])
    assert not np.isfinite(depth).any()
    # The quad's free edge x = 0 projects to column boundary 8; the degenerate triangles'
    # edges (boundary edges: no neighbour) lie on row boundary 8 from x = 1 (column 12.4)
    # to x = 3, the zero-length one at x = 1. Within 0.6 px: columns 7 and 8 along the quad,
    # rows 7 and 8 along the degenerate edges.
    near = silhouette_pixels(view, scene.occluder, 0.6).reshape(16, 16)
    assert near[2, 7] and near[2, 8] and not near[2, 6] and not near[2, 9]
    assert near[7, 12] and near[8, 12] and not near[6, 12]
    bad, _ = unexplained_pixels(scene, render_gl(scene).image, np.asarray(hj.render(scene)))
    assert bad.size == 0
    behind = scene.replace(occluder=hj.Occluder(kind="mesh", vertices=flat + [0, 0, 6], triangles=tris))
    assert hj.experimental.prepare(behind).occluder_pixel.size == 0
    gl_image = render_gl(behind).image
    assert np.all(gl_image[..., 3] < 1.0)
    np.testing.assert_allclose(gl_image, np.asarray(hj.render(behind)), atol=1e-4)
    # Off the map (and behind a point light's near plane): V = 1 whatever the map holds.
    light_view = hj.experimental.prepare(scene).view  # any view: points far outside its raster
    far = np.array([[1e6, 0.0, 0.0], [0.0, 0.0, 10.0]])
    np.testing.assert_array_equal(occluder_visibility(light_view, np.zeros(16 * 16), far), 1.0)


def test_fit_sees_the_occluder_receive_the_shadow():
    """hj.fit's image (hairjax/_fit/_kajiya_kay.py) includes the occluder's κ-dependent
    colour: on the slab scene the camera sees only the quad (k·ambient + e^{−κΩ}k; the hair is behind it),
    so κ is known from the occluder alone. A κ-only fit from 0.3 recovers 0.7 to 1e-6
    (the float64 solver's rtol is 1e-8) with RMSE < 1e-9."""
    scene = slab_scene("opacity-maps", kappa=0.7)
    target = np.asarray(hj.render(scene))
    p = scene.params
    start = hj.ShadingParams(kd=p.kd, ks=p.ks, shininess=p.shininess, ambient=p.ambient, kappa=0.3)
    r = hj.fit(scene, target, init=start, variables=("kappa",), stop=hj.FitStop(max_steps=50))
    np.testing.assert_allclose(float(r.params.kappa), 0.7, rtol=1e-6)
    assert r.rmse < 1e-9


def test_a_point_light_between_layers():
    """The quad-point-light scene by hand: the lower layer's points whose ray to the light
    (0, 1, 0) crosses y = 0.5 at x/2 ≤ −0.3 (x ≤ −0.6: x = −1, −0.75) are shadowed; the
    upper layer, behind the light's near plane, and the rest are lit."""
    scene = SCENES["quad-point-light"]
    v = np.asarray(hj.geometry_stage(scene).light_visibility).reshape(4, 9)
    expected = np.ones((4, 9))
    expected[:2, :2] = 0.0
    np.testing.assert_array_equal(v, expected)
