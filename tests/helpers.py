"""Small scenes and checks shared by the tests."""

from __future__ import annotations

from pathlib import Path

import numpy as np

import hairjax as hj
from hairjax._raster import rasterize
from hairjax._render import sphere_hits, visibility_order
from hairjax._shadows import light_frame

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data"


def load_experiment(name: str):
    """The module experiments/NAME.py (experiments/ is not a package)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(name, REPO / "experiments" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def small_furball_scene(strands=40, size=48, shadows="opacity-maps", maps=8, resolution=32,
                        alpha=0.6, **scene_kw) -> hj.Scene:
    hair = hj.furball(strands=strands, points=6, seed=3, alpha=alpha)
    return hj.Scene(
        strands=hair,
        camera=hj.Camera(eye=(0.0, 0.3, 3.5), target=(0.0, 0.0, 0.0), fov=45.0,
                         width=size, height=size),
        light=hj.Light(direction=(-0.5, -0.7, -0.4)),
        params=hj.ShadingParams(kd=(0.6, 0.4, 0.3), ks=0.4, shininess=20.0, kappa=0.8,
                                ambient=0.05),
        shadows=hj.Shadows(method=shadows, maps=maps, resolution=resolution),
        **scene_kw,
    )


def central_difference(f, x: float, eps: float) -> float:
    return (f(x + eps) - f(x - eps)) / (2 * eps)


# GL against JAX (tests/test_gl.py explains these tolerances and the bands below): every
# pixel (τ) differing by more than PIXEL_TOL (TAU_TOL) must lie where a discontinuity of
# the model is within float32 rounding, and such pixels must be rare (MAX_BAND).
PIXEL_TOL = 1e-4
TAU_TOL = 1e-4
SLICE_DELTA = 1e-4
MAX_BAND = 1e-3


def over_weights_numpy(alpha: np.ndarray, pixel: np.ndarray) -> np.ndarray:
    """Compositing weights α_k T_k (docs/model.md §6) of fragments sorted by pixel, front
    to back within a pixel, by cumulative products in NumPy: independent of the renderer's
    JAX scan, and no compilation per fragment count."""
    weights = np.empty(len(alpha))
    starts = np.flatnonzero(np.r_[True, pixel[1:] != pixel[:-1]]) if len(pixel) else np.zeros(0, int)
    for lo, hi in zip(starts, np.r_[starts[1:], len(pixel)]):
        transmitted = np.cumprod(1.0 - alpha[lo:hi])
        weights[lo:hi] = alpha[lo:hi] * np.r_[1.0, transmitted[:-1]]
    return weights


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
    weights = over_weights_numpy(alpha, pixel)
    at_risk = np.bincount(pixel, np.where(uncertain[sort], weights, 0.0),
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
    # Clipped before the cast: unseen points of a light at the hair's centre lie at ~1e300.
    tx = np.floor(np.clip(xy[:, 0], 0, r - 1)).astype(int)
    ty = np.floor(np.clip(xy[:, 1], 0, r - 1)).astype(int)
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
