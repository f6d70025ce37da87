"""Numerical stability, the part its tests share: the cases' scenes, the
compiled runner and the checks every case makes, on both renderers.

The tests are split by the stage they exercise, each file with its part of the table of
cases and of guards (double-where, clamp, safe norm, fallback: inputs that make each fire
and the guarded result checked against the model's value):

- tests/scene/test_stability.py: tangents of repeated points, procedural hair;
- tests/geometry/test_stability.py: projection, rasteriser, ordering, shadows, occluder,
  set-up, and coordinates at 1e-4 and 1e4;
- tests/shading/test_stability.py: Kajiya-Kay's power and gap, safe norms, shininess and κ
  at their extremes;
- tests/gl/test_stability.py: the GLSL guards and GL's depth test;
- tests/test_render_stability.py: compositing at extreme opacities, random scenes.

Every case runs on the JAX renderer in float64 and in float32 and on the GL renderer
(float32 only): `backend` ∈ {float64, float32, gl}. Scenes are small (≤ 32² pixels, 32²
maps, ≤ 4 maps). What every case checks (`check_jax`, `check_gl`):

- the image, Ω, the point colours and the gradients of Σ(image − target)² in Kd, Ks,
  ambient, shininess, κ and every strand's opacity are finite;
- 0 ≤ pixel ≤ the model's maximum (`channel_bound`: the composite is a convex combination
  of point colours and the backdrop, each bounded by ambient·c + light·(Kd·c + Ks));
- float64: those gradients equal central differences (`assert_matches_finite_differences`:
  the image is smooth in all of them everywhere, for every case);
- GL: equal to JAX float64 except where a model discontinuity within float32 rounding
  explains a difference (tests/gl/test_renderer.py's check, helpers.unexplained_pixels and
  shadow_band): the camera pass with JAX's Ω, and τ from GL's own Ω.

Each case's scene is compiled once per precision (`runner`), whichever file asks first;
the cache is this module's, so the files share it.

Not covered here: hairjax/_fit/ (the fit's guards are tested in tests/fit/test_fit.py).
"""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from helpers import (
    MAX_BAND,
    TAU_TOL,
    central_difference,
    shadow_band,
    unexplained_pixels,
)

import hairjax as hj
from hairjax._shading import point_colors

BACKENDS = ["float64", "float32", "gl"]
SIZE = 32  # every case renders 32 × 32 with 32² opacity maps: the rasteriser compiles once
# The module is compile-bound (a new scene means new array shapes): each scene × precision
# is compiled once, as one XLA program for loss, gradients and image, with XLA CPU's
# classic fusion emitters and LLVM at -O0 — the same HLO and IEEE arithmetic (results equal
# the default compilation's to ~1e-15 relative), 4× faster to compile than the default.
FAST_COMPILE = {"xla_backend_optimization_level": 0, "xla_cpu_use_fusion_emitters": False}
TARGET = dict(kd=(0.3, 0.5, 0.2), ks=0.1, shininess=8.0, kappa=2.0, ambient=0.05)


def unit_roundoff(dtype) -> float:
    return float(np.finfo(dtype).eps) / 2


# --- the model's maximum -------------------------------------------------------------------


def channel_bound(scene: hj.Scene, params: hj.ShadingParams, dtype) -> np.ndarray:
    """The largest value each RGB channel can take (`[3]`), with a rounding allowance.

    The bound (docs/model.md §6, §8, §9): C = Σ_k w_k c_k + T·B with w_k = α_k T_k ≥ 0 and
    Σ_k w_k + T = 1 (the products telescope), so C is a convex combination of fragment
    colours and the backdrop B. A fragment colour (1 − t)c(p₀) + t c(p₁), t ∈ [0, 1), lies
    between two point colours; a point colour ambient·c + τ·light·(Kd sin(T, L) c + Ks
    max(b, 0)^p) has τ = exp(−κΩ) ≤ 1 (κ, Ω ≥ 0), sin ≤ 1 and b = cos(θ_L ∓ θ_V) ≤ 1 for
    unit vectors; B is the background or the occluder's k·ambient + τ·V·k·light·max(N·L, 0)
    ≤ k·(ambient + light) (§13). So
    C ≤ max(ambient·c_max + light·(Kd·c_max + Ks), background, k·(ambient + light)) per channel.

    Rounding, u the unit roundoff: the unit vectors' norms are 1 ± u, so sin ≤ 1 + 3u and
    b, ~10 roundings, ≤ 1 + 16u, hence b^p ≤ exp(16pu) (p is b^p's condition number):
    1 + 2e-11 in float64 but 1.0096 at p = 10⁴ in float32. The weights and the sum over a
    pixel's n fragments (n ≤ the number of segments: one fragment per segment and pixel)
    carry ≤ 4nu relative error.
    """
    u = unit_roundoff(dtype)
    strands = scene.strands
    c_max = np.ones(3) if strands.color is None else strands.color.max(axis=0)
    light = np.asarray(scene.light.color)
    kd, ks, amb = (np.asarray(getattr(params, f), np.float64) for f in ("kd", "ks", "ambient"))
    p = float(params.shininess)
    hair = (amb * c_max + light * kd * c_max) * (1 + 8 * u) + light * ks * np.exp(16 * p * u)
    backdrop = np.asarray(scene.background)
    if scene.occluder is not None:
        backdrop = np.maximum(backdrop, np.asarray(scene.occluder.color) * (amb + light))
    n = len(strands.segments())
    return np.maximum(hair, backdrop) * (1 + 4 * n * u)


def assert_in_bounds(image, scene, params, dtype):
    image = np.asarray(image, np.float64)
    bound = channel_bound(scene, params, dtype)
    n = len(scene.strands.segments())
    # Every term is a product or sum of non-negative numbers: exactly ≥ 0.
    assert image.min() >= 0.0
    over = image[..., :3] - bound
    assert over.max() <= 0.0, f"a pixel exceeds the model's maximum {bound} by {over.max():.3g}"
    # alpha = 1 − Π(1 − α): within [0, 1] up to the weights' rounding.
    assert image[..., 3].max() <= 1.0 + 4 * n * unit_roundoff(dtype)


# --- running a case ------------------------------------------------------------------------


@dataclasses.dataclass
class Result:
    loss: float
    image: np.ndarray
    omega: np.ndarray | None
    colors: np.ndarray
    g_params: hj.ShadingParams
    g_alpha: np.ndarray


class Runner:
    """One scene in one precision: the loss Σ(image − target)², its gradients in the
    shading parameters and the per-strand opacity, the image, Ω and the point colours."""

    def __init__(self, scene: hj.Scene):
        self.scene = scene
        self.dtype = np.dtype(jnp.result_type(float))
        cam = scene.camera

        def loss(params, alpha, target):
            geometry = hj.geometry_stage(scene, alpha)
            image = hj.shading_stage(geometry, params)  # = hj.render(scene, params, alpha)
            aux = (image, geometry.omega, point_colors(geometry, params))
            return jnp.sum((image - target) ** 2), aux

        args = (scene.params, jnp.asarray(scene.strands.alpha), jnp.zeros((cam.height, cam.width, 4)))
        self._compiled = (
            jax.jit(jax.value_and_grad(loss, argnums=(0, 1), has_aux=True)).lower(*args).compile(FAST_COMPILE)
        )
        self._target = None

    @property
    def target(self):
        """The image at the TARGET parameters: the loss's target."""
        if self._target is None:
            self._target = jnp.asarray(self(hj.ShadingParams(**TARGET)).image)
        return self._target

    def __call__(self, params, alpha=None, target=None) -> Result:
        n = self.scene.strands.num_strands
        alpha = self.scene.strands.alpha if alpha is None else alpha
        alpha = jnp.broadcast_to(jnp.asarray(alpha, self.dtype), (n,))
        cam = self.scene.camera
        target = jnp.zeros((cam.height, cam.width, 4), self.dtype) if target is None else target
        (loss, (image, omega, colors)), (g_params, g_alpha) = self._compiled(params, alpha, target)
        return Result(
            float(loss),
            np.asarray(image),
            None if omega is None else np.asarray(omega),
            np.asarray(colors),
            g_params,
            np.asarray(g_alpha),
        )


def precision(backend: str):
    """The JAX precision a backend's scene is built in (GL compares with float64 JAX)."""
    return jax.enable_x64(backend != "float32")


_RUNNERS: dict = {}


def runner(case: str, dtype: str) -> Runner:
    """The case's scene and compiled loss in `dtype` (call inside `precision(dtype)`)."""
    key = (case, dtype)
    if key not in _RUNNERS:
        _RUNNERS[key] = Runner(CASES[case]())
    return _RUNNERS[key]


def finite(tree) -> bool:
    return all(bool(np.all(np.isfinite(np.asarray(x)))) for x in jax.tree_util.tree_leaves(tree))


FD_FIELDS = [("kd", 0), ("ks", 1), ("ambient", 2), ("shininess", None), ("kappa", None)]


def assert_matches_finite_differences(run: Runner, params, alpha, target, res: Result):
    """jax.grad against central differences (float64), along every shading parameter and
    the three opacities with the largest gradients.

    The image is smooth in all of them everywhere: the geometry (fragments, coverage, which
    point has b ≤ SPECULAR_BASE_EPS) does not depend on them, so the image is linear in Kd,
    Ks and ambient, smooth in p (b^p for a fixed b > 0), in κ (exp(−κΩ)) and a polynomial in
    each opacity times exp(−κΩ) with Ω linear in opacity. A central difference with step h
    then errs by
    - truncation h²|L'''|/6: relative to L' ≲ h²·(κ dΩ/da)², h²(ln b)², h²Ω² here, below
      1e-6 for h = 1e-6·max(|x|, 1) — the 1e-5 relative tolerance;
    - rounding: each pixel carries ≤ 4(n + 8)u relative error (`channel_bound`), so the
      loss Σ d², d = image − target, errs by ≤ Σ 2|d|·δ ≤ 4(n + 8)u·(L + Σ C²) with C the
      larger of image and target; divided by h — the absolute tolerance.
    """
    u = unit_roundoff(np.float64)
    n = len(run.scene.strands.segments())
    scale = res.loss + float(np.sum(np.maximum(np.abs(res.image), np.abs(np.asarray(target))) ** 2))

    def check(g, f, x):
        h = 1e-6 * max(abs(x), 1.0)
        fd = central_difference(f, x, h)
        rounding = 4 * (n + 8) * u * scale / h
        assert abs(g - fd) <= 1e-5 * abs(fd) + rounding, (g, fd, rounding)

    for field, i in FD_FIELDS:
        leaf = getattr(params, field)
        x = float(leaf if i is None else leaf[i])

        def f(v, field=field, i=i, leaf=leaf):
            new = jnp.asarray(v, leaf.dtype) if i is None else leaf.at[i].set(v)
            return run(eqx.tree_at(lambda p: getattr(p, field), params, new), alpha, target).loss

        g = getattr(res.g_params, field)
        check(float(g if i is None else g[i]), f, x)
    alpha = jnp.broadcast_to(jnp.asarray(alpha), res.g_alpha.shape)
    for j in np.argsort(-np.abs(res.g_alpha))[:3]:
        check(
            float(res.g_alpha[j]),
            lambda v, j=j: run(params, alpha.at[j].set(v), target).loss,
            float(alpha[j]),
        )


def check_jax(case: str, dtype: str, params_kw: dict | None = None, alpha=None) -> Result:
    """Render `case` in `dtype` (inside `precision(dtype)`): finite image and gradients,
    pixels within the model's maximum, and in float64 gradients equal to finite
    differences."""
    run = runner(case, dtype)
    params = hj.ShadingParams(**params_kw) if params_kw is not None else run.scene.params
    res = run(params, alpha, run.target)
    assert np.all(np.isfinite(res.image)), "image not finite"
    assert res.image.dtype == np.dtype(dtype)
    assert finite((res.g_params, res.g_alpha)), "gradient not finite"
    assert np.isfinite(res.colors).all() and (res.omega is None or np.isfinite(res.omega).all())
    assert_in_bounds(res.image, run.scene, params, dtype)
    if dtype == "float64":
        assert_matches_finite_differences(
            run, params, run.scene.strands.alpha if alpha is None else alpha, run.target, res
        )
    return res


def check_gl(case: str, params_kw: dict | None = None, alpha=None):
    """GL (float32) on `case` against JAX float64 (`compare_gl`)."""
    run = runner(case, "float64")
    params = hj.ShadingParams(**params_kw) if params_kw is not None else run.scene.params
    scene = run.scene
    if alpha is not None:
        a = np.broadcast_to(np.asarray(alpha, np.float64), (scene.strands.num_strands,))
        scene = scene.replace(strands=scene.strands.replace(alpha=a))
    ref = run(params, alpha)
    return compare_gl(scene, params, ref), ref


def compare_gl(scene: hj.Scene, params, ref: Result) -> np.ndarray:
    """GL on `scene`: finite, within the model's maximum, and equal to the JAX float64
    result `ref` except where a model discontinuity within float32 rounding explains it
    (the check of tests/gl/test_renderer.py): the camera pass with JAX's Ω, then τ from
    GL's own Ω.
    Returns GL's image (with its own Ω)."""
    from hairjax.gl import render_gl

    gl_image = render_gl(scene, params, omega=ref.omega).image
    assert np.all(np.isfinite(gl_image))
    assert_in_bounds(gl_image, scene, params, np.float32)
    bad, band = unexplained_pixels(scene, gl_image, ref.image)
    assert bad.size == 0, f"{bad.size} pixels differ from JAX with no boundary nearby"
    assert band.mean() <= MAX_BAND
    if scene.shadows.method == "none":
        return gl_image
    own = render_gl(scene, params)
    assert np.all(np.isfinite(own.image)) and np.all(np.isfinite(own.omega))
    assert_in_bounds(own.image, scene, params, np.float32)
    kappa = float(params.kappa)
    dtau = np.abs(np.exp(-kappa * own.omega.astype(np.float64)) - np.exp(-kappa * ref.omega))
    assert np.flatnonzero((dtau > TAU_TOL) & ~shadow_band(scene)).size == 0
    return own.image


def check(backend: str, request, case: str, params_kw: dict | None = None, alpha=None):
    """The generic checks of `backend` on `case`; returns (that backend's image, the JAX
    result of its precision — float64 for GL)."""
    if backend == "gl":
        request.getfixturevalue("gl")
        with precision("float64"):
            return check_gl(case, params_kw, alpha)
    with precision(backend):
        res = check_jax(case, backend, params_kw, alpha)
    return res.image, res


# --- the scenes ----------------------------------------------------------------------------

EYE = np.array([0.0, 0.0, 4.0])
FOCAL = 0.5 * SIZE / np.tan(np.radians(20.0))  # fov 40°: docs/model.md §2's f


def pixel_of(p) -> tuple[float, float]:
    """docs/model.md §2 by hand for the cases' camera (eye on +z looking at the origin)."""
    depth = EYE[2] - p[2]
    return SIZE / 2 + FOCAL * p[0] / depth, SIZE / 2 - FOCAL * p[1] / depth


def camera():
    return hj.Camera(eye=tuple(EYE), target=(0.0, 0.0, 0.0), fov=40.0, width=SIZE, height=SIZE)


# Strand indices of the mixed scene's special strands (after 24 fur-ball strands).
FUR = 24
THIN, WIDE, ALONG_L, ALONG_V, REPEATED, COINCIDENT, SINGLE = range(FUR, FUR + 7)
WIDE_Y, THIN_Y = -0.95, 1.1


def mixed_scene() -> hj.Scene:
    """A small fur ball with, around it, one strand of each extreme kind."""
    fur = hj.furball(FUR, 5, seed=1).transformed(0.5)
    special = [
        [[-0.7, THIN_Y, 0.0], [0.7, THIN_Y, 0.0]],  # THIN: width 0.25
        [[-0.7, WIDE_Y, 0.0], [0.7, WIDE_Y, 0.0]],  # WIDE: width 8
        np.stack([np.full(5, -1.1), np.linspace(0.8, -0.8, 5), np.zeros(5)], axis=1),  # T ∥ L
        [[0.0, 0.0, 1.0], [0.0, 0.0, 1.5], [0.0, 0.0, 2.0]],  # T ∥ V (on the axis)
        [[1.1, -0.6, 0.0], [1.1, -0.6, 0.0], [1.1, 0.0, 0.2], [1.1, 0.0, 0.2], [1.1, 0.6, 0.0]],
        [[-1.1, 1.1, 0.0]] * 3,  # COINCIDENT points
        [[1.1, 1.1, 0.0]],  # SINGLE point
    ]
    strands = [fur.points[fur.offsets[i] : fur.offsets[i + 1]] for i in range(FUR)] + special
    width = np.ones(len(strands))
    width[THIN], width[WIDE] = 0.25, 8.0
    hair = hj.Strands.from_list(strands, alpha=0.5)
    color = np.random.default_rng(0).uniform(0.0, 1.0, hair.points.shape)
    hair = hair.replace(width=width, color=color)
    return hj.Scene(
        hair,
        camera=camera(),
        light=hj.Light(direction=(0.0, -1.0, 0.0), color=(1.0, 0.9, 0.7)),
        shading=hj.KajiyaKay(hj.ShadingParams(kd=0.6, ks=0.4, shininess=20.0, kappa=0.8, ambient=0.05)),
        shadows=hj.Shadows("opacity-maps", 4, SIZE),
    )


def stack_scene() -> hj.Scene:
    """1200 strands stacked along the light (and view) axis: Ω reaches ~1100 and every
    pixel on the line composites 1200 fragments (T underflows to 0)."""
    n = 1200
    z = np.linspace(-0.5, 0.5, n)
    pts = np.stack([np.tile([-0.3, 0.0, 0.3], n), np.zeros(3 * n), np.repeat(z, 3)], axis=1)
    # Two one-point strands widen the light's map to 4 × 4 units: each ribbon spans only a
    # few texels there (fewer fragments), still covering its middle point's 3 × 3 box.
    pts = np.concatenate([pts, [[-2.0, -2.0, 0.0], [2.0, 2.0, 0.0]]])
    offsets = np.concatenate([np.arange(n + 1) * 3, [3 * n + 1, 3 * n + 2]])
    alpha = np.concatenate([np.random.default_rng(1).uniform(0.85, 1.0, n), [1.0, 1.0]])
    # Width 4: rows 14 … 17 of the map are fully covered around the line at y = 16.
    hair = hj.Strands(pts, offsets, alpha, 4.0)
    return hj.Scene(
        hair,
        camera=camera(),
        light=hj.Light(direction=(0.0, 0.0, -1.0)),
        shading=hj.KajiyaKay(hj.ShadingParams(kd=0.6, ks=0.4, shininess=20.0, kappa=2e-3, ambient=0.05)),
        shadows=hj.Shadows("opacity-maps", 4, SIZE),
    )


def point_light_scene(scale: float = 1.0) -> hj.Scene:
    """A fur ball lit by a point light sitting on one of its strand points."""
    hair = hj.furball(24, 5, seed=2, alpha=0.5).transformed(0.6)
    light = hair.points[LIGHT_POINT]
    return hj.Scene(
        hair.transformed(scale),
        camera=hj.Camera(eye=tuple(scale * EYE), target=(0.0, 0.0, 0.0), fov=40.0, width=SIZE, height=SIZE),
        light=hj.Light(kind="point", position=tuple(scale * light)),
        shading=hj.KajiyaKay(hj.ShadingParams(kd=0.6, ks=0.4, shininess=20.0, kappa=0.8, ambient=0.05)),
        shadows=hj.Shadows("exact", resolution=SIZE),
    )


LIGHT_POINT = 7  # an interior point of strand 1


def centre_light_scene() -> hj.Scene:
    """A point light at the fur ball's bounding-box centre: light_view looks down −y with
    near ≈ 1e-303, and the points level with the light project to ~1e300 (they raised a
    RuntimeWarning casting to texels before the clip in light_fragments)."""
    hair = hj.furball(30, 5, seed=6, alpha=0.5).transformed(0.6)
    centre = 0.5 * (hair.points.min(axis=0) + hair.points.max(axis=0))
    return hj.Scene(
        hair,
        camera=camera(),
        light=hj.Light(kind="point", position=tuple(centre)),
        shading=hj.KajiyaKay(hj.ShadingParams(**DEFAULT)),
        shadows=hj.Shadows("opacity-maps", 4, SIZE),
    )


def flat_scene() -> hj.Scene:
    """Every point at one depth from the camera and from a point light on the same axis."""
    fur = hj.furball(24, 5, seed=3, alpha=0.6).transformed(0.6)
    pts = fur.points * [1.0, 1.0, 0.0]
    # Two one-point strands make the bounding box symmetric: the light looks along −z.
    pts = np.concatenate([pts, [[-1.0, -1.0, 0.0], [1.0, 1.0, 0.0]]])
    offsets = np.concatenate([fur.offsets, [fur.offsets[-1] + 1, fur.offsets[-1] + 2]])
    hair = hj.Strands(pts, offsets, 0.6, 1.5)
    return hj.Scene(
        hair,
        camera=camera(),
        light=hj.Light(kind="point", position=(0.0, 0.0, 3.0)),
        shading=hj.KajiyaKay(hj.ShadingParams(kd=0.6, ks=0.4, shininess=20.0, kappa=0.8, ambient=0.05)),
        shadows=hj.Shadows("exact", resolution=SIZE),
    )


def inside_scene() -> hj.Scene:
    """The camera inside the fur ball (wide angle): points behind the eye and at the near
    plane."""
    hair = hj.furball(60, 6, seed=4, alpha=0.5)
    return hj.Scene(
        hair,
        camera=hj.Camera(eye=(0.05, 0.1, 0.02), target=(1.0, 0.2, 0.3), fov=90.0, width=SIZE, height=SIZE),
        light=hj.Light(direction=(-0.5, -0.7, -0.4)),
        shading=hj.KajiyaKay(hj.ShadingParams(kd=0.6, ks=0.4, shininess=20.0, kappa=0.8, ambient=0.05)),
        shadows=hj.Shadows("opacity-maps", 4, SIZE),
    )


CASES = {
    "mixed": mixed_scene,
    "stack": stack_scene,
    "point_light": point_light_scene,
    "point_light_1e-4": lambda: point_light_scene(1e-4),
    "point_light_1e4": lambda: point_light_scene(1e4),
    "flat": flat_scene,
    "centre_light": centre_light_scene,
    "inside": inside_scene,
}


DEFAULT = dict(kd=0.6, ks=0.4, shininess=20.0, kappa=0.8, ambient=0.05)


def runner_scene(case: str) -> hj.Scene:
    with precision("float64"):
        return runner(case, "float64").scene


# --- GLSL probes (the shading and GL parts) ------------------------------------------------

GLSL_PROBE = """#version 450
layout(local_size_x = 64) in;
#include "hairjax_model"
layout(std430, binding = 0) readonly buffer Inputs { float inp[]; };
layout(std430, binding = 1) writeonly buffer Outputs { float outp[]; };
uniform uint n;
%s
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= n) return;
%s
}
"""


def run_glsl(gl, body: str, inputs: np.ndarray, outputs: int, uniforms: str = "", **values) -> np.ndarray:
    """GLSL statements `body`, with model.glsl included, once per row i of `inputs` (`[n, k]`,
    read as inp[k·i + j]); they write outp[outputs·i + j]. Returns `[n, outputs]` float32."""
    from hairjax.gl._context import release
    from hairjax.gl._programs import programs

    programs(gl)  # registers the "hairjax_model" include
    inputs = np.ascontiguousarray(inputs, np.float32)
    n = len(inputs)
    shader = gl.compute_shader(GLSL_PROBE % (uniforms, body))
    src, dst = gl.buffer(inputs.tobytes()), gl.buffer(reserve=4 * outputs * n)
    try:
        src.bind_to_storage_buffer(0)
        dst.bind_to_storage_buffer(1)
        shader["n"] = n
        for name, value in values.items():
            shader[name] = value
        shader.run((n + 63) // 64)
        return np.frombuffer(dst.read(), np.float32).reshape(n, outputs).copy()
    finally:
        release(gl, shader, src, dst)


def glsl_highlight(gl, t, light, eye, model: str, p: float) -> np.ndarray:
    """model.glsl on rows (T, L, V): `[n, 2]` of (Ks·max(b, 0)^p from shade_point with Ks = 1
    and nothing else, the renderer's path; kajiya_kay_gap)."""
    body = """
    vec3 T = vec3(inp[9u * i], inp[9u * i + 1u], inp[9u * i + 2u]);
    vec3 L = vec3(inp[9u * i + 3u], inp[9u * i + 4u], inp[9u * i + 5u]);
    vec3 V = vec3(inp[9u * i + 6u], inp[9u * i + 7u], inp[9u * i + 8u]);
    Shading s = Shading(vec3(0.0), vec3(1.0), vec3(0.0), p, 0.0, model);
    outp[2u * i] = shade_point(s, T, L, V, vec3(1.0), vec3(1.0), 1.0).x;
    outp[2u * i + 1u] = kajiya_kay_gap(model, dot(T, L), dot(T, V), safe_norm(cross(T, L)),
                                       safe_norm(cross(T, V)));"""
    return run_glsl(
        gl,
        body,
        np.concatenate([t, light, eye], axis=1),
        2,
        "uniform int model;\nuniform float p;",
        model=hj.extend.shading_model_class(model).gl_id,
        p=p,
    )


def glsl_marschner_lobes(gl, t, light, eye, params: hj.MarschnerParams) -> np.ndarray:
    """model.glsl's marschner_lobes on rows (T, L, V), with the uniforms the renderer sets
    (`Marschner.gl_uniforms`): `[n, 7]` of (R, TT rgb, TRT rgb)."""
    body = """
    vec3 T = vec3(inp[9u * i], inp[9u * i + 1u], inp[9u * i + 2u]);
    vec3 L = vec3(inp[9u * i + 3u], inp[9u * i + 4u], inp[9u * i + 5u]);
    vec3 V = vec3(inp[9u * i + 6u], inp[9u * i + 7u], inp[9u * i + 8u]);
    float r;
    vec3 tt, trt;
    marschner_lobes(marschner, T, L, V, r, tt, trt);
    outp[7u * i] = r;
    for (uint c = 0u; c < 3u; c++) {
        outp[7u * i + 1u + c] = tt[c];
        outp[7u * i + 4u + c] = trt[c];
    }"""
    uniforms = hj.Marschner(params).gl_uniforms(params)
    values = {k: v for k, v in uniforms.items() if k.startswith("marschner.")}
    rows = np.concatenate([t, light, eye], axis=1)
    return run_glsl(gl, body, rows, 7, "uniform Marschner marschner;", **values)


def jax_marschner_lobes(t, light, eye, params: hj.MarschnerParams) -> np.ndarray:
    """The JAX model's lobes (hairjax/_shading/_marschner_lobes.py, float64) on rows
    (T, L, V), as `[n, 7]` of (R, TT rgb, TRT rgb)."""
    from hairjax._shading._marschner import absorption
    from hairjax._shading._marschner_lobes import marschner_lobes

    lobes = jax.vmap(marschner_lobes, in_axes=(0, 0, 0, None, None, None))(
        *(jnp.asarray(x, jnp.float64) for x in (t, light, eye)),
        absorption(params),
        params.longitudinal_roughness,
        params.tilt,
    )
    r, tt, trt = (np.asarray(x) for x in lobes)
    return np.concatenate([r[:, None], tt, trt], axis=1)


def glsl_dual_terms(gl, t, light, eye, count, params: hj.MarschnerParams) -> np.ndarray:
    """model.glsl's dual_terms on rows (T, L, V, n) with the renderer's uniforms and tables
    texture (`Marschner.gl_uniforms`, `gl_table`): `[n, 18]`, direct then scattered, each
    `[lobe (R, TT, TRT), RGB]` flattened."""
    from hairjax.gl._context import release

    model = hj.Marschner(params, multiple_scattering="dual")
    table = np.ascontiguousarray(model.gl_table(params), dtype="f4")
    texture = gl.texture((table.shape[1], table.shape[0]), 3, table.tobytes(), dtype="f4")
    body = """
    vec3 T = vec3(inp[10u * i], inp[10u * i + 1u], inp[10u * i + 2u]);
    vec3 L = vec3(inp[10u * i + 3u], inp[10u * i + 4u], inp[10u * i + 5u]);
    vec3 V = vec3(inp[10u * i + 6u], inp[10u * i + 7u], inp[10u * i + 8u]);
    vec3 direct[3], scattered[3];
    dual_terms(marschner, marschner_tables, T, L, V, inp[10u * i + 9u], direct, scattered);
    for (uint p = 0u; p < 3u; p++) {
        for (uint c = 0u; c < 3u; c++) {
            outp[18u * i + 3u * p + c] = direct[p][c];
            outp[18u * i + 9u + 3u * p + c] = scattered[p][c];
        }
    }"""
    uniforms = model.gl_uniforms(params)
    values = {k: v for k, v in uniforms.items() if k.startswith("marschner.")}
    rows = np.concatenate([t, light, eye, np.asarray(count, np.float32)[:, None]], axis=1)
    try:
        texture.use(0)
        declarations = "uniform Marschner marschner;\nuniform sampler2D marschner_tables;"
        return run_glsl(gl, body, rows, 18, declarations, marschner_tables=0, **values)
    finally:
        release(gl, texture)


def jax_dual_terms(t, light, eye, count, params: hj.MarschnerParams) -> np.ndarray:
    """The JAX model's dual_terms (hairjax/_shading/_dual_scattering.py, float64) on the
    same rows, as `[n, 18]` (direct then scattered, `[lobe, RGB]` flattened)."""
    from hairjax._shading._dual_scattering import dual_tables, dual_terms_batched
    from hairjax._shading._marschner import absorption

    beta, tilt = params.longitudinal_roughness, params.tilt
    tables = dual_tables(absorption(params), beta, tilt)
    direct, scattered = dual_terms_batched(
        *(jnp.asarray(x, jnp.float64) for x in (t, light, eye, count)), tables, beta, tilt
    )
    n = len(t)
    return np.concatenate([np.asarray(direct).reshape(n, 9), np.asarray(scattered).reshape(n, 9)], axis=1)
