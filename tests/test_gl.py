"""GL renderer against the JAX renderer, pixel by pixel and point by point (issue 3).

The model has discontinuities (docs/model.md §5, §7, §9): a pixel centre belongs to a
segment only for 0 ≤ s < L; a light-space fragment adds to the slice its depth falls in;
a pixel is the occluder's if its centre's ray hits the sphere. GLSL computes in float32,
JAX here in float64, so a pixel or point within rounding distance of such a boundary may
fall on different sides. Every difference above the tolerance must be explained by one,
and those must be rare; a wrong shader must leave differences no boundary explains.

Tolerances:
- 1e-4 per pixel / per τ: float32 arithmetic on values ≤ 1 with ~10² operations per
  fragment and up to ~10³ fragments composited per pixel gives errors ~10⁻⁵ (measured
  RMSE 4e-6 … 7e-5 on these scenes); 1e-4 is the issue's bound.
- δ = 4 ulp of the raster's largest coordinate (2.4e-4 px at 512, 1.2e-4 at 256) for
  "near a segment end": GL projects points in float32, so screen coordinates carry about
  one ulp of error and s = (c − p₀)·u a few; 4 ulps is the measured envelope (at 2 ulps
  the default scene leaves unexplained pixels, at 4 none).
- 1e-4 slice units for "near a slice boundary": depth relative error ~1e-7, times N/span.
- a pixel is in the band when the fragments that may toggle there weigh enough to move it
  by > 1e-4 (weight α·T times the brightest colour); the band may hold at most 0.1 % of
  pixels (the issue's bound).
"""

from __future__ import annotations

from pathlib import Path

import jax.numpy as jnp
import numpy as np
import pytest
from helpers import DATA

import hairjax as hj
from hairjax._composite import over_weights
from hairjax._raster import rasterize
from hairjax._render import sphere_hits, visibility_order
from hairjax._shadows import light_frame

EXAMPLES = Path(__file__).resolve().parents[1] / "experiments" / "scenes"
PIXEL_TOL = 1e-4
TAU_TOL = 1e-4
SLICE_DELTA = 1e-4
MAX_BAND = 1e-3


def load(name):
    if name == "default":
        return hj.load_scene(hj.default_scene_path())
    if name == "tressfx_ponytail" and not DATA.is_dir():
        pytest.skip("shared/data is not beside the checkout")
    return hj.load_scene(EXAMPLES / f"{name}.toml")


SCENES = ["default", "point_light", "grazing", "dense_opaque", "occluder", "tressfx_ponytail"]


def s_delta(w, h) -> float:
    """4 float32 ulps of the raster's largest coordinate."""
    return 4 * float(np.spacing(np.float32(max(w, h))))


def end_band(xy0, xy1, z0, z1, width, w, h, perspective):
    """Fragments of the ribbons lengthened by δ at both ends, and which of them lie within
    δ of an end (present lengthened, absent shortened by δ)."""
    S_DELTA = s_delta(w, h)  # noqa: N806
    d = xy1 - xy0
    u = d / np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-300)
    grow = rasterize(xy0 - S_DELTA * u, xy1 + S_DELTA * u, z0, z1, width, w, h, perspective)
    shrink = rasterize(xy0 + S_DELTA * u, xy1 - S_DELTA * u, z0, z1, width, w, h, perspective)
    key = lambda f: f.segment.astype(np.int64) * (w * h) + f.pixel  # noqa: E731
    return grow, ~np.isin(key(grow), key(shrink))


def camera_band(scene, colour_bound: float) -> np.ndarray:
    """Pixels (row-major) a camera-side discontinuity within rounding can change by more
    than PIXEL_TOL. A fragment that may or may not be drawn changes its pixel by at most
    w·colour_bound, w = α·T its compositing weight (docs/model.md §6), so a pixel is in
    the band when the uncertain fragments' weights sum above PIXEL_TOL / colour_bound."""
    cam = scene.camera
    view, xy, depth, segments, order = visibility_order(scene)
    near_first = order[::-1]
    s0, s1 = segments[near_first, 0], segments[near_first, 1]
    strand = scene.strands.strand_of_point[s0]
    frags, uncertain = end_band(xy[s0], xy[s1], depth[s0], depth[s1],
                                scene.strands.width[strand], cam.width, cam.height, True)
    sort = np.argsort(frags.pixel, kind="stable")  # front to back within a pixel
    pixel = frags.pixel[sort]
    alpha = scene.strands.alpha[strand[frags.segment[sort]]] * frags.coverage[sort]
    first = np.r_[True, pixel[1:] != pixel[:-1]]
    weights, _ = over_weights(jnp.asarray(alpha), jnp.asarray(first), jnp.asarray(np.r_[first[1:], True]))
    at_risk = np.bincount(pixel, np.where(uncertain[sort], np.asarray(weights), 0.0),
                          minlength=cam.width * cam.height)
    band = at_risk * colour_bound > PIXEL_TOL
    if scene.occluder is not None:
        # The sphere's silhouette, and hair fragments at the sphere's own depth.
        origin, direction = view.pixel_rays()
        oc = origin - np.asarray(scene.occluder.center)
        b = np.sum(oc * direction, axis=1)
        disc = b * b - (np.sum(oc * oc, axis=1) - scene.occluder.radius**2)
        band |= np.abs(disc) < 1e-4 * scene.occluder.radius**2
        hit, _, _ = sphere_hits(view, scene.occluder)
        close = np.abs(frags.depth - hit[frags.pixel]) < 1e-5 * np.abs(hit[frags.pixel])
        band[frags.pixel[close]] = True
    return band


def shadow_band(scene) -> np.ndarray:
    """Points whose Ω may depend on a light-side discontinuity within rounding: a fragment
    near a segment end or a slice boundary in their 3 × 3 texels, or the point itself
    near a texel edge."""
    s = scene.strands
    r = scene.shadows.resolution
    segs = s.segments()
    frame = light_frame(s.points, segs, s.width, scene.light, r)
    ids = frame.drawable
    a, b = segs[ids, 0], segs[ids, 1]
    width = s.width[s.strand_of_point[a]]
    xy, z = frame.xy, frame.depth
    frags, near_end = end_band(xy[a], xy[b], z[a], z[b], width, r, r, frame.view.perspective)
    uncertain = np.zeros(r * r, bool)
    uncertain[frags.pixel[near_end]] = True
    if scene.shadows.method == "opacity-maps":
        u = frame.slice_coordinate(frags.depth, scene.shadows.maps)
        near_plane = np.abs(u - np.round(u)) < SLICE_DELTA
        uncertain[frags.pixel[near_plane]] = True
    grid = uncertain.reshape(r, r)
    # Dilate by the filter: a point sees its 3 × 3 texels.
    padded = np.pad(grid, 1)
    dilated = np.zeros_like(grid)
    for dy in range(3):
        for dx in range(3):
            dilated |= padded[dy:dy + r, dx:dx + r]
    tx = np.clip(np.floor(xy[:, 0]).astype(int), 0, r - 1)
    ty = np.clip(np.floor(xy[:, 1]).astype(int), 0, r - 1)
    frac = xy - np.floor(xy)
    near_edge = (np.minimum(frac, 1 - frac) < 1e-4).any(axis=1)
    band = dilated[ty, tx] | near_edge
    if scene.shadows.method == "exact":
        # Ω counts fragments strictly nearer than the point: a fragment within 4 float32
        # ulps of the point's own depth, in its 3 × 3 texels, is a tie either way.
        dz = 4 * float(np.spacing(np.float32(np.abs(z).max())))
        order = np.lexsort((frags.depth, frags.pixel))
        key_t, key_z = frags.pixel[order], frags.depth[order]
        composite = key_t + 0.5 * (key_z - z.min() + dz) / (np.ptp(z) + 4 * dz)
        for oy in (-1, 0, 1):
            for ox in (-1, 0, 1):
                t = np.clip(ty + oy, 0, r - 1) * r + np.clip(tx + ox, 0, r - 1)
                lo = np.searchsorted(composite, t + 0.5 * (z - dz - z.min() + dz) / (np.ptp(z) + 4 * dz))
                hi = np.searchsorted(composite, t + 0.5 * (z + dz - z.min() + dz) / (np.ptp(z) + 4 * dz))
                band |= hi > lo
    return band


def unexplained_pixels(scene, gl_image, jax_image):
    diff = np.abs(gl_image - jax_image).max(axis=-1).ravel()
    # Any fragment's colour and what lies behind it are ≤ the brightest pixel value, so a
    # toggled fragment changes a pixel by at most its weight times that.
    band = camera_band(scene, colour_bound=float(np.max(jax_image[..., :3])))
    return np.flatnonzero((diff > PIXEL_TOL) & ~band), band


@pytest.fixture(scope="module")
def references():
    """JAX image and Ω per scene, computed once (float64)."""
    cache = {}

    def get(name):
        if name not in cache:
            scene = load(name)
            geom = hj.geometry_stage(scene)
            cache[name] = scene, np.asarray(hj.shading_stage(geom, scene.params)), (
                None if geom.omega is None else np.asarray(geom.omega))
        return cache[name]

    return get


@pytest.mark.parametrize("name", SCENES)
def test_camera_pass_matches(gl, references, name):
    """With the same Ω, GL's image equals JAX's except in a band explained by boundaries."""
    from hairjax.gl import render_gl

    scene, jax_image, omega = references(name)
    result = render_gl(scene, omega=omega)
    assert result.image.shape == jax_image.shape and np.all(np.isfinite(result.image))
    bad, band = unexplained_pixels(scene, result.image, jax_image)
    assert bad.size == 0, f"{bad.size} pixels differ by > {PIXEL_TOL} with no boundary nearby"
    assert band.mean() <= MAX_BAND
    assert np.abs(result.image - jax_image).max() > 0 or scene.strands.num_strands == 0


@pytest.mark.parametrize("name", SCENES)
def test_transmittance_matches(gl, references, name):
    """GL's Ω (its own opacity maps) gives τ within 1e-4 of JAX's except at points a
    light-side boundary explains."""
    from hairjax.gl import render_gl

    scene, _, omega = references(name)
    if omega is None:
        pytest.skip("scene without shadows")
    result = render_gl(scene)
    kappa = float(scene.params.kappa)
    dtau = np.abs(np.exp(-kappa * result.omega.astype(np.float64)) - np.exp(-kappa * omega))
    band = shadow_band(scene)
    bad = np.flatnonzero((dtau > TAU_TOL) & ~band)
    assert bad.size == 0, f"{bad.size} points' τ differ by > {TAU_TOL} with no boundary nearby"
    # The full image then differs only where a camera boundary or an explained τ is.
    assert np.mean(dtau > TAU_TOL) <= MAX_BAND * 10


def test_exact_shadows_match(gl):
    from hairjax.gl import render_gl

    scene = load("point_light").replace(shadows=hj.Shadows("exact", resolution=128))
    omega = np.asarray(hj.geometry_stage(scene).omega)
    result = render_gl(scene)
    kappa = float(scene.params.kappa)
    dtau = np.abs(np.exp(-kappa * result.omega) - np.exp(-kappa * omega))
    band = shadow_band(scene)
    assert np.flatnonzero((dtau > TAU_TOL) & ~band).size == 0
    assert np.median(dtau) < 1e-6


@pytest.mark.parametrize("model", ["kajiya-kay", "kajiya-kay-mirror"])
def test_both_shading_conventions(gl, model):
    from hairjax.gl import render_gl

    scene = load("point_light").replace(shading_model=model, shadows=hj.Shadows("none"))
    jax_image = np.asarray(hj.render(scene))
    bad, _ = unexplained_pixels(scene, render_gl(scene).image, jax_image)
    assert bad.size == 0


def test_a_wrong_shader_fails_the_check(gl, references, monkeypatch):
    """Flip the sign of the seed's specular term in GLSL: the check must catch it."""
    from hairjax.gl import _programs, render_gl

    scene, jax_image, omega = references("point_light")
    original = _programs.shader_source

    def flipped(name):
        text = original(name)
        if name == "model.glsl":
            assert "tl * tv + sin_tl * sin_tv" in text
            text = text.replace("tl * tv + sin_tl * sin_tv", "tl * tv - sin_tl * sin_tv")
        return text

    monkeypatch.setattr(_programs, "shader_source", flipped)
    _programs.clear_cache()
    try:
        wrong = render_gl(scene, omega=omega).image
    finally:
        monkeypatch.undo()
        _programs.clear_cache()
    bad, _ = unexplained_pixels(scene, wrong, jax_image)
    assert bad.size > 100
    # And the correct shader passes again afterwards.
    bad, _ = unexplained_pixels(scene, render_gl(scene, omega=omega).image, jax_image)
    assert bad.size == 0
