"""Numerical stability (issue 5 §2): extreme and stiff cases on both renderers.

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
  explains a difference (tests/test_gl.py's check, helpers.unexplained_pixels and
  shadow_band): the camera pass with JAX's Ω, and τ from GL's own Ω.

The cases (issue 5 §2's list) and what they add:

| case                            | test_…                                  | scene: own assertions          |
|---------------------------------|-----------------------------------------|--------------------------------|
| shininess 0.5 … 10⁴             | shininess_extremes                      | mixed, flat (b ≈ 1 at centre)  |
| b^p near its peak at p = 10⁴    | highlight_accuracy_at_p_1e4             | vs float64: ~sqrt(2p)·u bound  |
| κ 0 … 10³                       | kappa_extremes                          | mixed                          |
| opacity 10⁻⁶ … 1                | opacity_extremes                        | mixed: alpha ≤ n·a; a = 1 → 1  |
| width 0.25 … 8 px               | widths_quarter_and_eight_pixels         | mixed: a·coverage by hand      |
| Ω in the thousands              | omega_in_the_thousands                  | stack: Ω = Σ others' a ≈ 1100  |
| T ∥ L, T ∥ V                    | tangents_parallel_to_light_and_view     | mixed: colours by hand         |
| point light at a strand point   | point_light_at_a_strand_point           | ambient there; Ω = 0 off map   |
| point light at the hair centre  | point_light_at_the_hairs_centre         | Ω = 0 for the unseen points    |
| zero-length, repeated points    | zero_length_segments_and_repeated_points| ambient·c exactly, not drawn   |
| all points at one depth         | all_points_at_one_depth                 | flat: Ω = 0 exactly (both Ω)   |
| camera inside the hair          | camera_inside_the_hair                  | inside                         |
| coordinates ~1e4 and ~1e-4      | coordinates_around_1e4_and_1e_minus_4   | = unscaled image and gradients |
| GL depth test at 1e-4           | gl_depth_test_keeps_its_resolution_…    | occluder, by hand              |
| random scenes                   | random_scenes                           | hypothesis, all ranges at once |

Found here: (1) GL's depth test floored `far` at 2 units, so a scene 1e-4 units across
resolved depth to 4e-4 (hair just in front of the occluder vanished): fixed in
gl/_renderer.py. (2) A point light at the hair's bounding-box centre raised a RuntimeWarning
(texel cast of ~1e300): fixed in _shadows.shadow_setup. (3) A camera up of length < 1e-9
(or within 1e-9 rad of forward, which Camera accepts) turned the image by 90°: fixed in
_projection._basis. (4) At p = 10⁴ and b ≈ 1, float32 (GL and JAX alike) erred by 2.4e-4
on `flat` (b^p has condition number p in b, and b was rounded): fixed in
_shading.kajiya_kay_terms / specular_power and model.glsl, which carry the gap
1 − b = s²/(1 + b), s = sin(θ_L ∓ θ_V), and take b^p = exp(p·log1p(−gap)) (GLSL with its
own log1p: llvmpipe's log is inaccurate just below 1); now < 1e-6 there, ≤ 3e-5 relative
near any peak (test_highlight_accuracy_at_p_1e4, against 2.7e-3 before).

Every guard (double-where, clamp, safe norm, fallback) and the test that reaches it — with
inputs that make it fire and the guarded result checked against the model's value:

| guard (file: function)                          | test_guard_… (or test_… in full)            |
|-------------------------------------------------|---------------------------------------------|
| _render: tangents/_unit, zero difference        | zero_tangent_of_repeated_points             |
| _render: to_light/_unit, point light at a point | test_point_light_at_a_strand_point          |
| _occluder: sphere_hits sqrt(where(disc ≥ 0))    | sphere_rays_that_miss_and_an_eye_inside     |
| _occluder: sphere_hits far root (eye inside)    | sphere_rays_that_miss_and_an_eye_inside     |
| _occluder: sphere_hits _unit(point − centre)    | unreachable: hits at the radius, misses out |
| _render: _prepare Lambert clip (max(N·L, 0))    | sphere_rays_that_miss_and_an_eye_inside     |
| _occluder: vertex_normals/_unit, zero sum       | test_occluder::…degenerate_triangles_…      |
| _occluder: mesh_hits zero-area projections      | test_occluder::…degenerate_triangles_…      |
| _occluder: _near_segments zero-length edge      | test_occluder::…degenerate_triangles_…      |
| _occluder: occluder_visibility off the map      | test_occluder::…degenerate_triangles_…      |
| _vectors: safe_norm double-where                | safe_norm_at_zero                           |
| _vectors: safe_normalize (unused by renderer)   | safe_normalize_of_zero                      |
| _shading: specular_power double-where           | specular_power_at_and_below_the_cut         |
| _shading: kajiya_kay_terms double-where, b ≤ 0  | kajiya_kay_gap_on_the_far_side              |
| _shadows: map_margin initial=1.0                | map_margin_without_strands                  |
| _shadows: light_frame span fallback             | light_sees_all_points_at_one_depth          |
| _shadows: light_frame, no point seen            | no_point_in_front_of_a_point_light          |
| _shadows: shadow_setup texel clip (new)         | test_point_light_at_the_hairs_centre        |
| _shadows: shadow_setup slice clip [0, N]        | fragment_below_the_nearest_plane (rounding) |
| _shadows: shadow_setup exact key clip, valid    | no_point_in_front_of_a_point_light          |
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
| _raster: _candidates padding guards             | rasteriser_padding_columns                  |
| _raster: _candidates za == zb                   | constant_depth_fragments_keep_z             |
| _sources: _unit_vectors, _grow                  | fur_sources                                 |
| _sources: scalp clip(1 − y², 0)                 | unreachable: |y| ≤ 1 gives fl(y²) ≤ 1       |
| model.glsl: project max(z, near)                | test_camera_inside_the_hair[gl]             |
| model.glsl: fragment_depth z0 == z1             | test_all_points_at_one_depth[gl]            |
| model.glsl: safe_norm                           | test_tangents_parallel_to_light_and_view[gl]|
| model.glsl: specular_power                      | test_shininess_extremes[mixed-0.5-gl]       |
| model.glsl: kajiya_kay_gap, b ≤ 0               | glsl_kajiya_kay_gap_and_log1p               |
| model.glsl: log1p_accurate, x ∉ (−½, 1)         | glsl_kajiya_kay_gap_and_log1p               |
| model.glsl: slice_of clamp                      | test_all_points_at_one_depth[gl] (maps)     |
| ribbon.geom: zero-length segments               | test_zero_length_segments_…_points[gl]      |
| strand.vert: safe_normalize                     | test_point_light_at_a_strand_point[gl]      |
| omega_maps.comp: outside the map, f clamp       | test_point_light_at_the_hairs_centre[gl]    |
| omega_exact.comp: texels outside the map        | test_point_light_at_a_strand_point[gl]      |
| occluder_sphere.frag: t > 0                     | point_light_on_the_occluder (eye outside)   |
| occluder_color.frag: light on the surface       | point_light_on_the_occluder                 |
| occluder_mesh.frag: zero interpolated normal    | unreachable in practice: only at a vertex   |
|                                                 | whose faces' normals cancel exactly         |
| occluder_visibility.comp: off the map           | not reached by a test (JAX's is, above)     |
| gl/_renderer: no drawable triangle              | test_occluder::…a_mesh_behind_the_eye       |
| gl/_renderer: empty buffers, ortho near         | exact_shadows_without_fragments             |
| gl/_renderer: depth_far (fixed)                 | test_gl_depth_test_keeps_its_resolution_…   |

Not audited: hairjax/_fit/ (outside this issue's brief; its guards are tested in
tests/test_fit.py).
"""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import (
    MAX_BAND,
    TAU_TOL,
    central_difference,
    cone,
    shadow_band,
    shadow_method,
    unexplained_pixels,
)
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

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


# --- running a case ----------------------------------------------------------------------

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

        args = (scene.params, jnp.asarray(scene.strands.alpha),
                jnp.zeros((cam.height, cam.width, 4)))
        self._compiled = jax.jit(jax.value_and_grad(loss, argnums=(0, 1), has_aux=True)).lower(
            *args).compile(FAST_COMPILE)
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
        return Result(float(loss), np.asarray(image), None if omega is None else np.asarray(omega),
                      np.asarray(colors), g_params, np.asarray(g_alpha))


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
        check(float(res.g_alpha[j]),
              lambda v, j=j: run(params, alpha.at[j].set(v), target).loss, float(alpha[j]))


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
        assert_matches_finite_differences(run, params, run.scene.strands.alpha if alpha is None
                                          else alpha, run.target, res)
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
    (the check of tests/test_gl.py): the camera pass with JAX's Ω, then τ from GL's own Ω.
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


# --- the scenes -----------------------------------------------------------------------------

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
        [[-0.7, THIN_Y, 0.0], [0.7, THIN_Y, 0.0]],                      # THIN: width 0.25
        [[-0.7, WIDE_Y, 0.0], [0.7, WIDE_Y, 0.0]],                      # WIDE: width 8
        np.stack([np.full(5, -1.1), np.linspace(0.8, -0.8, 5), np.zeros(5)], axis=1),  # T ∥ L
        [[0.0, 0.0, 1.0], [0.0, 0.0, 1.5], [0.0, 0.0, 2.0]],            # T ∥ V (on the axis)
        [[1.1, -0.6, 0.0], [1.1, -0.6, 0.0], [1.1, 0.0, 0.2], [1.1, 0.0, 0.2], [1.1, 0.6, 0.0]],
        [[-1.1, 1.1, 0.0]] * 3,                                          # COINCIDENT points
        [[1.1, 1.1, 0.0]],                                               # SINGLE point
    ]
    strands = [fur.points[fur.offsets[i]:fur.offsets[i + 1]] for i in range(FUR)] + special
    width = np.ones(len(strands))
    width[THIN], width[WIDE] = 0.25, 8.0
    hair = hj.Strands.from_list(strands, alpha=0.5)
    color = np.random.default_rng(0).uniform(0.0, 1.0, hair.points.shape)
    hair = hair.replace(width=width, color=color)
    return hj.Scene(hair, camera=camera(), light=hj.Light(direction=(0.0, -1.0, 0.0),
                                                          color=(1.0, 0.9, 0.7)),
                    shading=hj.KajiyaKay(hj.ShadingParams(kd=0.6, ks=0.4, shininess=20.0, kappa=0.8, ambient=0.05)),
                    shadows=hj.Shadows("opacity-maps", 4, SIZE))


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
    return hj.Scene(hair, camera=camera(), light=hj.Light(direction=(0.0, 0.0, -1.0)),
                    shading=hj.KajiyaKay(hj.ShadingParams(kd=0.6, ks=0.4, shininess=20.0, kappa=2e-3, ambient=0.05)),
                    shadows=hj.Shadows("opacity-maps", 4, SIZE))


def point_light_scene(scale: float = 1.0) -> hj.Scene:
    """A fur ball lit by a point light sitting on one of its strand points."""
    hair = hj.furball(24, 5, seed=2, alpha=0.5).transformed(0.6)
    light = hair.points[LIGHT_POINT]
    return hj.Scene(hair.transformed(scale),
                    camera=hj.Camera(eye=tuple(scale * EYE), target=(0.0, 0.0, 0.0), fov=40.0,
                                     width=SIZE, height=SIZE),
                    light=hj.Light(kind="point", position=tuple(scale * light)),
                    shading=hj.KajiyaKay(hj.ShadingParams(kd=0.6, ks=0.4, shininess=20.0, kappa=0.8, ambient=0.05)),
                    shadows=hj.Shadows("exact", resolution=SIZE))


LIGHT_POINT = 7  # an interior point of strand 1


def centre_light_scene() -> hj.Scene:
    """A point light at the fur ball's bounding-box centre: light_view looks down −y with
    near ≈ 1e-303, and the points level with the light project to ~1e300 (they raised a
    RuntimeWarning casting to texels before the clip in shadow_setup)."""
    hair = hj.furball(30, 5, seed=6, alpha=0.5).transformed(0.6)
    centre = 0.5 * (hair.points.min(axis=0) + hair.points.max(axis=0))
    return hj.Scene(hair, camera=camera(), light=hj.Light(kind="point", position=tuple(centre)),
                    shading=hj.KajiyaKay(hj.ShadingParams(**DEFAULT)), shadows=hj.Shadows("opacity-maps", 4, SIZE))


def flat_scene() -> hj.Scene:
    """Every point at one depth from the camera and from a point light on the same axis."""
    fur = hj.furball(24, 5, seed=3, alpha=0.6).transformed(0.6)
    pts = fur.points * [1.0, 1.0, 0.0]
    # Two one-point strands make the bounding box symmetric: the light looks along −z.
    pts = np.concatenate([pts, [[-1.0, -1.0, 0.0], [1.0, 1.0, 0.0]]])
    offsets = np.concatenate([fur.offsets, [fur.offsets[-1] + 1, fur.offsets[-1] + 2]])
    hair = hj.Strands(pts, offsets, 0.6, 1.5)
    return hj.Scene(hair, camera=camera(), light=hj.Light(kind="point", position=(0.0, 0.0, 3.0)),
                    shading=hj.KajiyaKay(hj.ShadingParams(kd=0.6, ks=0.4, shininess=20.0, kappa=0.8, ambient=0.05)),
                    shadows=hj.Shadows("exact", resolution=SIZE))


def inside_scene() -> hj.Scene:
    """The camera inside the fur ball (wide angle): points behind the eye and at the near
    plane."""
    hair = hj.furball(60, 6, seed=4, alpha=0.5)
    return hj.Scene(hair, camera=hj.Camera(eye=(0.05, 0.1, 0.02), target=(1.0, 0.2, 0.3), fov=90.0,
                                           width=SIZE, height=SIZE),
                    light=hj.Light(direction=(-0.5, -0.7, -0.4)),
                    shading=hj.KajiyaKay(hj.ShadingParams(kd=0.6, ks=0.4, shininess=20.0, kappa=0.8, ambient=0.05)),
                    shadows=hj.Shadows("opacity-maps", 4, SIZE))


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


# --- the cases -------------------------------------------------------------------------------

DEFAULT = dict(kd=0.6, ks=0.4, shininess=20.0, kappa=0.8, ambient=0.05)


def coverage_by_hand(d: float, w: float) -> float:
    """docs/model.md §5's cross-ribbon coverage, written out independently of _raster."""
    return min(max(min(d + 0.5, w / 2) - max(d - 0.5, -w / 2), 0.0), 1.0)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("shininess", [0.5, 1e4])
@pytest.mark.parametrize("case", ["mixed", "flat"])
def test_shininess_extremes(request, backend, shininess, case):
    """p = 0.5 (b^p steep at b = 0) and p = 10⁴ (a needle highlight; in `flat` the light
    sits next to the eye, so b ≈ 1 around the centre and the float32 rounding of b matters:
    see test_highlight_accuracy_at_p_1e4)."""
    check(backend, request, case, dict(DEFAULT, shininess=shininess))


def near_peak_directions(model: str, n: int, p: float, rng) -> tuple[np.ndarray, ...]:
    """`n` float32 unit (T, L, V) around the highlight's peak: θ_L uniform in [0.05, π − 0.05],
    θ_V = θ_L + δ (mirror: π − θ_L + δ) with p(1 − cos δ) ≤ 2, i.e. b^p ≥ e⁻², and L, V at
    random azimuths about T (b depends on the angles only); the last rows have L = V (mirror:
    V = L reflected in the plane normal to T), b = 1 up to the rounding to float32."""
    t = rng.normal(size=(n, 3))
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    e1 = rng.normal(size=(n, 3))
    e1 -= np.sum(e1 * t, axis=1, keepdims=True) * t
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(t, e1)
    theta_l = rng.uniform(0.05, np.pi - 0.05, n)
    delta = rng.uniform(-1.0, 1.0, n) * np.arccos(1 - 2 / p)
    delta[-8:] = 0.0
    theta_v = theta_l + delta if model == "kajiya-kay" else np.pi - theta_l + delta

    def direction(theta, phi):
        around = np.cos(phi)[:, None] * e1 + np.sin(phi)[:, None] * e2
        return np.cos(theta)[:, None] * t + np.sin(theta)[:, None] * around

    phi_l, phi_v = rng.uniform(0.0, 2 * np.pi, (2, n))
    phi_v[-8:] = phi_l[-8:]
    return tuple(x.astype(np.float32) for x in (t, direction(theta_l, phi_l), direction(theta_v, phi_v)))


def highlight_by_angles(t, light, eye, model: str, p: float) -> np.ndarray:
    """max(b, 0)^p in float64 for the directions of the (float32) vectors, from the angles:
    b = cos Δ, Δ = θ_L − θ_V (kajiya-kay) or θ_L + θ_V − π (mirror: −cos(θ_L + θ_V)), so
    1 − b = 2 sin²(Δ/2) without cancellation. The vectors are normalised first: the model is
    defined for unit vectors, and their float32 norms 1 ± u would move b by O(u) — the very
    error under test (float64 rendering sees unit vectors to 1e-16)."""
    t, light, eye = (np.asarray(x, np.float64) for x in (t, light, eye))
    t, light, eye = (x / np.linalg.norm(x, axis=1, keepdims=True) for x in (t, light, eye))

    def angle(x):
        return np.arctan2(np.linalg.norm(np.cross(t, x), axis=1), np.sum(t * x, axis=1))

    delta = angle(light) - angle(eye) if model == "kajiya-kay" else angle(light) + angle(eye) - np.pi
    gap = 2 * np.sin(delta / 2) ** 2
    return np.where(gap < 1, np.exp(p * np.log1p(-np.minimum(gap, 1.0))), 0.0)


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
    return run_glsl(gl, body, np.concatenate([t, light, eye], axis=1), 2,
                    "uniform int model;\nuniform float p;", model=hj.shading_model_class(model).gl_id, p=p)


@pytest.mark.parametrize("model", ["kajiya-kay", "kajiya-kay-mirror"])
@pytest.mark.parametrize("backend", ["float32", "gl"])
def test_highlight_accuracy_at_p_1e4(request, backend, model):
    """b^p at p = 10⁴ near its peak (b^p ≥ e⁻²), in float32 — kajiya_kay_terms +
    specular_power in JAX, shade_point in GLSL — against the model in float64 at the same
    float32 directions, to the bound below; and the old exp(p·log b), b rounded in float32,
    fails that bound (the control: the gap 1 − b = s²/(1 + b) is what makes the difference).
    The errors are printed (pytest -s).

    The bound, u = 2⁻²⁴: with s = sin(θ_L ∓ θ_V), g = 1 − b = s²/(1 + b), x = p·g ≈ −ln b^p ≤ 2:
    - cos θ = T·X errs by ≤ 3u, sin θ = ‖T × X‖ by ≤ 6u (3u the cross product, 2.5u the
      norm), so s = sin θ_L cos θ_V ∓ cos θ_L sin θ_V by |δs| ≤ 6u(|cos θ_L| + |cos θ_V|) +
      3u(sin θ_L + sin θ_V) + 2u ≤ (2√45 + 2)u < 16u (absolute: s → 0 at the peak);
    - g then errs by 2|δs|/|s| relative, plus ~12u (the square, 1 + b, the division, the
      inputs' norms 1 ± u scaling s² and 1 + b alike), and b^p = exp(p·log1p(−g)) by
      p·δg plus a few u·(x + 1) (log1p, the product, exp: GLSL allows 3 + 2x ulps);
    - p·g·2|δs|/|s| = 2x|δs|/|s| and |s| = sqrt(g(1 + b)) ≈ sqrt(2x/p) give
      relative error ≤ 16u·sqrt(2p·x) + 64u ≤ 32u·sqrt(p) + 64u = 1.95e-4 (x ≤ 2, p = 10⁴).
    Rounding b itself (the old formula) errs by p·|δb| with |δb| a few u: ~1e-3."""
    from hairjax._shading import kajiya_kay_terms, specular_power

    p = 1e4
    u = unit_roundoff(np.float32)
    bound = 32 * u * np.sqrt(p) + 64 * u
    t, light, eye = near_peak_directions(model, 4096, p, np.random.default_rng(11))
    exact = highlight_by_angles(t, light, eye, model, p)
    assert exact.min() >= np.exp(-2.0) * (1 - 1e-9)
    if backend == "gl":
        got = glsl_highlight(request.getfixturevalue("gl"), t, light, eye, model, p)[:, 0]
    else:
        with precision("float32"):
            power = jax.jit(jax.vmap(lambda a, b, c: specular_power(kajiya_kay_terms(a, b, c, cone(model))[1],
                                                                    jnp.float32(p))))
            got = np.asarray(power(t, light, eye))
        assert got.dtype == np.float32
    err = np.max(np.abs(got.astype(np.float64) - exact) / exact)
    # The control: b = (T·L)(T·V) ± sin sin rounded in float32, then exp(p·log b) in float32.
    tl, tv = np.sum(t * light, axis=1), np.sum(t * eye, axis=1)
    sl, sv = (np.linalg.norm(np.cross(t, x), axis=1) for x in (light, eye))
    b = tl * tv + sl * sv if model == "kajiya-kay" else sl * sv - tl * tv
    assert b.dtype == np.float32
    old = np.exp(np.float32(p) * np.log(b))
    old_err = np.max(np.abs(old.astype(np.float64) - exact) / exact)
    print(f"\n{backend} {model}, p = 1e4, b^p ≥ e^-2: max relative error {err:.3g} "
          f"(bound {bound:.3g}); old exp(p·log b) in float32: {old_err:.3g}")
    assert err <= bound, (err, bound)
    assert old_err > bound, (old_err, bound)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("kappa", [0.0, 1e3])
def test_kappa_extremes(request, backend, kappa):
    """κ = 0 (no shadow) and κ = 10³ (τ underflows to 0 wherever Ω > 0.75)."""
    check(backend, request, "mixed", dict(DEFAULT, kappa=kappa))


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("alpha", [1e-6, 1.0])
def test_opacity_extremes(request, backend, alpha):
    """a = 10⁻⁶ everywhere (the hair all but vanishes) and a = 1 (T = 0 exactly behind a
    fully covered fragment: the product scan, not exp Σ log(1 − α))."""
    image, _ = check(backend, request, "mixed", alpha=alpha)
    n = len(runner_scene("mixed").strands.segments())
    if alpha == 1.0:
        # The wide ribbon covers whole pixels: opaque there, exactly.
        assert image[..., 3].max() == 1.0
    else:
        # 1 − Π(1 − a·coverage) ≤ n·a for a pixel's ≤ n fragments.
        assert 0 < image[..., 3].max() <= n * alpha


def runner_scene(case: str) -> hj.Scene:
    with precision("float64"):
        return runner(case, "float64").scene


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
    fur = runner_scene("mixed").strands.points[:runner_scene("mixed").strands.offsets[FUR]]
    fur_rows = np.array([pixel_of(p)[1] for p in fur])
    assert fur_rows.min() > 6 and fur_rows.max() < 23
    # The thin ribbon never covers more than its width.
    assert alpha[2:6].max() <= 0.25 * a + tol


def kajiya_kay_by_hand(t, light, eye):
    """(sin(T, L), b) of docs/model.md §8 (the seed's model) for unit T, L, V, in NumPy."""
    sin_tl, sin_tv = np.linalg.norm(np.cross(t, light)), np.linalg.norm(np.cross(t, eye))
    return sin_tl, (t @ light) * (t @ eye) + sin_tl * sin_tv


@pytest.mark.parametrize("backend", BACKENDS)
def test_tangents_parallel_to_light_and_view(request, backend):
    """T ∥ L: sin(T, L) = ‖T × L‖ = 0 exactly (safe_norm's guard), so no diffuse light and
    b = (T·L)(T·V). T ∥ V (a strand on the camera axis, drawn as nothing but shaded): b =
    (T·L)(T·V) = 0 here. The point colours equal those values by hand; the gradients are
    finite although safe_norm sits at its kink (check_jax); GL draws the T ∥ L strand as
    JAX does (check_gl)."""
    _, res = check(backend, request, "mixed")
    if backend == "gl":
        return
    dtype = backend
    scene = runner_scene("mixed")
    s, pts, c = scene.strands, scene.strands.points, scene.strands.color
    light = np.array([0.0, 1.0, 0.0])
    rgb = np.asarray(scene.light.color)
    p = DEFAULT["shininess"]
    tau = np.exp(-DEFAULT["kappa"] * res.omega)
    # b^p amplifies b's rounding by p; every other factor carries a few roundings.
    rtol = 16 * (p + 4) * unit_roundoff(np.dtype(dtype))
    for strand, tangent in ((ALONG_L, np.array([0.0, -1.0, 0.0])), (ALONG_V, np.array([0.0, 0.0, 1.0]))):
        for i in range(s.offsets[strand], s.offsets[strand + 1]):
            eye = (EYE - pts[i]) / np.linalg.norm(EYE - pts[i])
            sin_tl, b = kajiya_kay_by_hand(tangent, light, eye)
            expected = DEFAULT["ambient"] * c[i] + tau[i] * rgb * (
                DEFAULT["kd"] * sin_tl * c[i] + DEFAULT["ks"] * max(b, 0.0) ** p)
            np.testing.assert_allclose(res.colors[i], expected, rtol=rtol, atol=rtol)
    # Seen from the light, the strand along L is a row of zero-length ribbons: it draws
    # nothing there and casts no shadow, not even on itself.
    np.testing.assert_array_equal(res.omega[s.offsets[ALONG_L]:s.offsets[ALONG_L + 1]], 0.0)


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
        np.testing.assert_array_equal(res.colors[zero_tangent],
                                      dtype.type(DEFAULT["ambient"]) * s.color[zero_tangent].astype(dtype))


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
        np.testing.assert_array_equal(res.colors[LIGHT_POINT], np.full(3, DEFAULT["ambient"],
                                                                        res.colors.dtype))
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
            omegas = [res.omega, np.asarray(hj.geometry_stage(
                scene.replace(shadows=hj.Shadows("opacity-maps", 4, SIZE))).omega)]
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
        assert_same_setup(hj.prepare(runner(case, backend).scene), hj.prepare(base.scene), u)
    rel = 1000 * (DEFAULT["shininess"] + 8) * u
    bound = channel_bound(base.scene, base.scene.params, np.dtype(backend)).max()
    assert np.abs(image - ref.image).max() <= rel * bound
    for got, want in zip(jax.tree_util.tree_leaves((res.g_params, res.g_alpha)),
                         jax.tree_util.tree_leaves((ref.g_params, ref.g_alpha))):
        assert np.abs(np.asarray(got) - np.asarray(want)).max() <= rel * np.abs(np.asarray(want)).max()


def test_gl_depth_test_keeps_its_resolution_at_1e_minus_4(gl):
    """Hair just in front of / just behind the occluder (relative depth gaps 3e-5 … 3e-4,
    beyond test_gl's 1e-5 band for "at the sphere's depth") in a scene 10⁻⁴ units across:
    GL's depth test must classify each like JAX. The depth buffer stores depth/far in 2⁻²⁴
    steps; with `far` floored at 2 units the step was 4e-4 of these depths (bug, fixed in
    _camera_pass)."""
    from hairjax._geometry._projection import camera_view
    from hairjax.gl import render_gl

    s = 1e-4
    cam = hj.Camera(eye=(0.0, 0.0, 4 * s), target=(0.0, 0.0, 0.0), fov=40.0, width=33, height=33)
    origin, direction = camera_view(cam).pixel_rays()
    rows = np.arange(6, 28, 2)  # rows whose centre ray meets the sphere (|row − 16| < 11.7)
    gaps = np.geomspace(3e-5, 3e-4, len(rows)) * np.where(np.arange(len(rows)) % 2, -1, 1)
    strands, lambert = [], []
    for row, gap in zip(rows, gaps):
        o, d = origin[row * 33 + 16], direction[row * 33 + 16]
        # The ray's first hit on the sphere of radius s at the origin, by hand.
        b = o @ d
        t = -b - np.sqrt(b * b - (o @ o - s * s))
        lambert.append((o + t * d)[2] / s)  # N·L with L = +z
        _, y, z = o + t * (1 - gap) * d  # a horizontal hair at the hit's depth × (1 − gap)
        strands.append([[-0.3 * s, y, z], [0.3 * s, y, z]])
    scene = hj.Scene(hj.Strands.from_list(strands, alpha=1.0), camera=cam,
                     light=hj.Light(direction=(0.0, 0.0, -1.0)),
                     occluder=hj.Occluder(center=(0.0, 0.0, 0.0), radius=s, color=(0.2, 0.2, 0.2)),
                     shadows=hj.Shadows("none"), shading=hj.KajiyaKay(hj.ShadingParams(kd=0.0, ks=0.0, ambient=1.0)))
    jax_image = np.asarray(hj.render(scene))
    gl_image = render_gl(scene).image
    # By hand: hair in front (gap > 0) shows white (it runs through the pixel centre:
    # coverage 1 up to the projection's rounding, ~1e-13), behind it the sphere's
    # 0.2·(ambient + N·L), ambient 1 (§13). GL: the same to float32 rounding (a few ulps).
    expected = np.where(gaps > 0, 1.0, 0.2 * (1.0 + np.asarray(lambert)))
    np.testing.assert_allclose(jax_image[rows, 16, 0], expected, rtol=0, atol=1e-12)
    np.testing.assert_allclose(gl_image[rows, 16, 0], expected, rtol=0, atol=1e-6)
    bad, _ = unexplained_pixels(scene, gl_image, jax_image)
    assert bad.size == 0


# --- the guards -------------------------------------------------------------------------------
# One test per guard (the table in the module docstring): inputs that make it fire, and the
# guarded result checked against the model's value.

def test_guard_zero_tangent_of_repeated_points():
    """_render.tangents/_unit: a zero central difference (repeated points, one-point
    strands) gives the zero tangent, exactly; other tangents are unit vectors."""
    from hairjax._scene._strands import tangents

    hair = hj.Strands.from_list([[[0, 0, 0], [0, 0, 0], [1, 0, 0]],       # one-sided p1 − p0 = 0
                                 [[2, 2, 2]],                              # one point
                                 [[0, 1, 0], [0, 1, 0], [0, 1, 0]],       # all equal
                                 [[0, 0, 0], [1, 2, 2], [0, 0, 0]]])      # p2 − p0 = 0 (middle)
    t = tangents(hair.points, hair.offsets)
    zero = [0, 3, 4, 5, 6, 8]
    np.testing.assert_array_equal(t[zero], 0.0)
    np.testing.assert_allclose(np.linalg.norm(np.delete(t, zero, axis=0), axis=1), 1.0, rtol=1e-15)


@pytest.mark.parametrize("dtype", ["float64", "float32"])
def test_guard_safe_norm_at_zero(dtype):
    """_vectors.safe_norm's double-where: ‖0‖ = 0 with gradient 0 (not NaN); in float64
    below SAFE_NORM_EPS too (in float32 SAFE_NORM_EPS² underflows: only exact zeros fire,
    as in GLSL). Reached in the renderer by T ∥ L, T ∥ V and zero tangents: sin = 0 and a
    finite gradient with respect to the tangent."""
    from hairjax._constants import SAFE_NORM_EPS
    from hairjax._vectors import safe_norm

    with precision(dtype):
        for v in ([0.0, 0.0, 0.0], [0.0, 1e-31, 0.0] if dtype == "float64" else [0.0, 0.0, 0.0]):
            x = jnp.asarray(v)
            value, grad = jax.value_and_grad(safe_norm)(x)
            assert float(value) == 0.0 and np.all(np.asarray(grad) == 0.0)
        x = jnp.asarray([0.0, 1e3 * SAFE_NORM_EPS if dtype == "float64" else 1e-10, 0.0])
        assert float(safe_norm(x)) == float(x[1])  # above the cut: the norm itself
        t = jnp.asarray([0.0, 1.0, 0.0])
        params = hj.ShadingParams(kd=0.7, ks=0.5, shininess=1e4)

        def shade(t, v):
            d, s = hj.kajiya_kay(t, t, v, params)  # T ∥ L
            return jnp.sum(d + s)

        grad_shade = jax.jit(jax.value_and_grad(shade))
        for v in (t, jnp.asarray([0.6, 0.8, 0.0])):  # also T ∥ V
            value, grad = grad_shade(t, v)
            assert np.isfinite(float(value)) and np.all(np.isfinite(np.asarray(grad)))
        d, _ = hj.kajiya_kay(t, t, jnp.asarray([0.6, 0.8, 0.0]), params)
        np.testing.assert_array_equal(d, 0.0)


def test_guard_safe_normalize_of_zero():
    """_vectors.safe_normalize (GLSL strand.vert's twin): 0 ↦ 0 with a finite gradient."""
    from hairjax._vectors import safe_normalize

    zero = jnp.zeros(3)
    np.testing.assert_array_equal(safe_normalize(zero), 0.0)
    jac = jax.jacobian(safe_normalize)(zero)
    assert np.all(np.isfinite(np.asarray(jac)))
    np.testing.assert_allclose(safe_normalize(jnp.asarray([3.0, 0.0, 4.0])), [0.6, 0.0, 0.8], rtol=1e-15)


@pytest.mark.parametrize("dtype", ["float64", "float32"])
def test_guard_specular_power_at_and_below_the_cut(dtype):
    """_shading.specular_power's double-where: for b = 1 − gap ≤ SPECULAR_BASE_EPS (b < 0 on
    the cone's far side, b = 0 with p = 0.5 where d(b^p)/db = ∞, log 0 = −∞ in d/dp) the
    value and both gradients are exactly 0; just above the cut, b^p by hand. The jump at the
    cut: ≤ eps^0.5 = 1e-6 in float64 (the reason for the constant's value); in float32 the
    smallest base above it is 2⁻²⁴ (1 − gap with gap's resolution at 1), a jump of 2.4e-4 —
    within b^0.5's error from b's own absolute rounding (~u: b ≈ 0 is a cancelling sum)."""
    from hairjax._constants import SPECULAR_BASE_EPS
    from hairjax._shading import specular_power

    with precision(dtype):
        f = jax.value_and_grad(specular_power, argnums=(0, 1))
        one = np.dtype(dtype).type(1.0)
        # Gaps whose b = 1 − gap (exact: Sterbenz) is −0.3, 0, 1e-13, ≤ SPECULAR_BASE_EPS.
        at_cut = one - np.dtype(dtype).type(SPECULAR_BASE_EPS)
        at_cut = at_cut if one - at_cut <= SPECULAR_BASE_EPS else np.nextafter(at_cut, 2 * one)
        for gap in (one + np.dtype(dtype).type(0.3), one, one - np.dtype(dtype).type(1e-13), at_cut):
            assert one - gap <= SPECULAR_BASE_EPS
            for p in (0.5, 1e4):
                value, (gg, gp) = f(jnp.asarray(gap), jnp.asarray(p))
                assert float(value) == 0.0 and float(gg) == 0.0 and float(gp) == 0.0
        gap = min(one - np.dtype(dtype).type(2 * SPECULAR_BASE_EPS), np.nextafter(one, 0 * one))
        b = float(one - gap)  # 2e-12 in float64, 2⁻²⁴ in float32
        assert b > SPECULAR_BASE_EPS
        value, (gg, gp) = f(jnp.asarray(gap), jnp.asarray(0.5))
        u = unit_roundoff(np.dtype(dtype))
        # exp(p·log1p(−gap)): log1p and the product carry a few ulps, times |p·log b| ≤ 13.5.
        np.testing.assert_allclose(float(value), np.sqrt(b), rtol=64 * u)
        np.testing.assert_allclose(float(gg), -0.5 / np.sqrt(b), rtol=64 * u)
        np.testing.assert_allclose(float(gp), np.sqrt(b) * np.log(b), rtol=64 * u)
        assert np.sqrt(SPECULAR_BASE_EPS) <= 1e-6
        assert float(value) <= np.sqrt(max(2 * SPECULAR_BASE_EPS, 2 * u)) * (1 + 64 * u)


@pytest.mark.parametrize("dtype", ["float64", "float32"])
def test_guard_kajiya_kay_gap_on_the_far_side(dtype):
    """_shading.kajiya_kay_terms' double-where: where b ≤ 0 the gap is 1 − b, not
    s²/(1 + b), which is 0/0 at b = −1 (kajiya-kay: T ∥ L, V = −T; mirror: T ∥ L ∥ V) — and
    its gradient NaN. There, and at b = 0 (T ⟂ L, T ∥ V) and b = −0.75: gap = 1 − b by hand,
    b^p = 0 and every gradient (T, L, V, p) exactly 0."""
    from hairjax._shading import kajiya_kay_terms, specular_power

    x, y = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
    w = np.array([0.6614378, 0.75, 0.0])  # T·w = 0.75 for T = y (w unit to 1e-8; exact b)
    cases = [("kajiya-kay", x, x, -x, -1.0), ("kajiya-kay-mirror", x, x, x, -1.0),
             ("kajiya-kay", x, y, x, 0.0), ("kajiya-kay", y, w, -y, -0.75),
             ("kajiya-kay-mirror", y, w, y, -0.75)]
    with precision(dtype):
        for model, t, light, eye, b in cases:
            t, light, eye = (jnp.asarray(a) for a in (t, light, eye))

            def power(t, light, eye, p, model=model):
                return specular_power(kajiya_kay_terms(t, light, eye, cone(model))[1], p)

            _, gap = kajiya_kay_terms(t, light, eye, cone(model))
            assert float(gap) == 1.0 - b, (model, float(gap), b)
            value, grads = jax.value_and_grad(power, argnums=(0, 1, 2, 3))(t, light, eye, jnp.asarray(1e4))
            assert float(value) == 0.0
            assert all(np.all(np.asarray(g) == 0.0) for g in grads), (model, grads)
            grad_gap = jax.grad(lambda t, light, eye, model=model: kajiya_kay_terms(
                t, light, eye, cone(model))[1], argnums=(0, 1, 2))(t, light, eye)
            assert finite(grad_gap)


def test_guard_glsl_kajiya_kay_gap_and_log1p(gl):
    """model.glsl: kajiya_kay_gap's b ≤ 0 branch on the cases of
    test_guard_kajiya_kay_gap_on_the_far_side (b = −1, where s²/(1 + b) is 0/0; 0; −0.75):
    gap = 1 − b by hand, and shade_point's Ks·b^p exactly 0 (specular_power's cut). And
    log1p_accurate's branches: the atanh series for −½ < x < 1 (down to x below ulp(1)/2,
    where 1 + x = 1) and log(1 + x) outside, each within 16u of float64 log1p (GLSL allows
    division 2.5 ulps and log 3 ulps, 2⁻²¹ absolute on [0.5, 2]; llvmpipe: ≤ 3u), where
    plain log(1 + x) is off by 10⁵ u and more near 0 (asserted: the reason for the function)."""
    x, y = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
    w = np.array([0.6614378, 0.75, 0.0])
    for model, rows, b in (("kajiya-kay", [(x, x, -x), (x, y, x), (y, w, -y)], [-1.0, 0.0, -0.75]),
                           ("kajiya-kay-mirror", [(x, x, x), (y, w, y)], [-1.0, -0.75])):
        t, light, eye = (np.array(c, np.float32) for c in zip(*rows))
        out = glsl_highlight(gl, t, light, eye, model, 1e4)
        np.testing.assert_array_equal(out[:, 1], 1.0 - np.float32(b))
        np.testing.assert_array_equal(out[:, 0], 0.0)
        for p in (0.5, 1.0):
            np.testing.assert_array_equal(glsl_highlight(gl, t, light, eye, model, p)[:, 0], 0.0)
    xs = np.concatenate([-np.geomspace(1e-9, 0.49, 60), np.geomspace(1e-9, 0.99, 60),
                         [-0.5, -0.75, -0.999, 1.0, 3.0, 1e3]]).astype(np.float32)
    body = "    outp[2u * i] = log1p_accurate(inp[i]);\n    outp[2u * i + 1u] = log(1.0 + inp[i]);"
    out = run_glsl(gl, body, xs[:, None], 2)
    exact = np.log1p(xs.astype(np.float64))
    rel = np.abs(out.astype(np.float64) - exact[:, None]) / np.abs(exact[:, None])
    u = unit_roundoff(np.float32)
    assert rel[:, 0].max() <= 16 * u, xs[np.argmax(rel[:, 0])]
    assert rel[:, 1].max() >= 1e5 * u  # plain log(1 + x): 1 + x rounds away x's low bits


def test_guard_light_sees_all_points_at_one_depth():
    """_shadows.light_frame's span fallback: every point at one light depth gives span 1
    (any positive spacing: nothing is strictly nearer than anything, Ω = 0, asserted on
    both renderers in test_all_points_at_one_depth)."""
    from hairjax._geometry._shadows import light_frame

    pts = np.array([[0.0, 0.0, 0.0], [1.0, 0.5, 0.0], [-0.5, 1.0, 0.0]])
    frame = light_frame(pts, np.array([[0, 1], [1, 2]]), np.ones(1),
                        hj.Light(direction=(0.0, 0.0, -1.0)), 16)
    assert np.ptp(frame.depth) == 0.0 and frame.span == 1.0


def test_guard_no_point_in_front_of_a_point_light():
    """A point light at its hair's bounding-box centre, every point level with it:
    light_view looks down −y (axis fallback), near = 1e-3·max(0, 1e-300), the field of
    view falls back to ±80°; light_frame sees no point (zmin = 0, span 1); every point
    gets Ω = 0 (texel −1 for the maps, zero weights for `exact`)."""
    from hairjax._geometry._shadows import exact_opacity, light_frame, point_opacity, shadow_setup

    pts = np.array([[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    segs = np.array([[0, 1]])
    light = hj.Light(kind="point", position=(0.0, 0.0, 0.0))
    frame = light_frame(pts, segs, np.ones(1), light, 16)
    np.testing.assert_array_equal(frame.view.forward, [0.0, -1.0, 0.0])
    assert frame.view.near == 1e-3 * 1e-300 and not frame.seen.any()
    assert (frame.zmin, frame.span) == (0.0, 1.0) and frame.drawable.size == 0
    # usable = 16 − 2·margin(width 1) = 12 texels over ±80°.
    assert frame.view.focal == pytest.approx(6 / np.tan(np.radians(80.0)), rel=1e-12)
    maps = shadow_setup(pts, segs, np.zeros(1, int), np.ones(1), light, hj.Shadows("opacity-maps", 2, 16))
    np.testing.assert_array_equal(maps.texel, -1)
    omega = point_opacity(jnp.ones((3, 16, 16)), jnp.asarray(maps.plane), jnp.asarray(maps.f),
                          jnp.asarray(maps.texel))
    np.testing.assert_array_equal(omega, 0.0)
    exact = shadow_setup(pts, segs, np.zeros(1, int), np.ones(1), light, hj.Shadows("exact", resolution=16))
    np.testing.assert_array_equal(exact.weight, 0.0)
    np.testing.assert_array_equal(exact_opacity(jnp.zeros(0), jnp.zeros(0, bool),
                                                jnp.asarray(exact.index), jnp.asarray(exact.weight)), 0.0)


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

    view = View(np.zeros(3), np.array([0.0, 0.0, -1.0]), np.array([1.0, 0, 0]), np.array([0, 1.0, 0]),
                8, 8, 1.0, 4.0, 4.0, False, -np.inf)
    depth = np.array([1.0, 2.0, 3.0, 0.5])  # D₀ = 1, D_N = 3; the last one unseen
    frame = LightFrame(view, np.zeros((4, 2)), depth, np.array([True, True, True, False]),
                       np.zeros(0, int), 1.0, 2.0)
    plane, f = point_planes(frame, 4)
    np.testing.assert_array_equal(plane, [0, 2, 3, 0])
    np.testing.assert_array_equal(f, [0.0, 0.0, 1.0, 0.0])


def test_guard_fragment_below_the_nearest_plane(monkeypatch):
    """_shadows.shadow_setup's slice clip: a light-space fragment whose interpolated depth
    rounds below D₀ (u slightly < 0, only through rounding) goes to slice 0 (it counts for
    planes 1 … N), never to slice −1; one at D_N to slice N (beyond the last plane)."""
    import dataclasses as dc

    import hairjax._geometry._shadows as shadows_mod
    import hairjax._geometry._shadows._frame as frame_mod

    real = frame_mod.rasterize

    def nudged(*args):
        frags = real(*args)
        depth = frags.depth.copy()
        depth[np.argmin(depth)] = np.nextafter(depth.min(), -np.inf)  # one ulp below D₀
        return dc.replace(frags, depth=depth)

    monkeypatch.setattr(frame_mod, "rasterize", nudged)
    hair = hj.furball(6, 4, seed=1)
    segs = hair.segments()
    setup = shadows_mod.shadow_setup(hair.points, segs, hair.strand_of_point[segs[:, 0]], hair.width,
                                     hj.Light(direction=(0.3, -1.0, 0.2)), hj.Shadows("opacity-maps", 4, 16))
    slices = setup.frag_cell // 16**2
    assert slices.min() == 0 and slices.max() <= 4


def test_guard_exact_shadows_without_fragments(request):
    """_shadows.exact_opacity's empty guard (and GL's empty-buffer guards): hair of
    one-point strands and zero-length segments draws no light-space fragment: Ω = 0 on
    both renderers; the image is the background."""
    hair = hj.Strands.from_list([[[0.0, 0.0, 0.0]], [[0.5, 0.2, 0.0], [0.5, 0.2, 0.0]]], alpha=0.7)
    scene = hj.Scene(hair, camera=camera(), shadows=hj.Shadows("exact", resolution=SIZE),
                     background=(0.1, 0.2, 0.3))
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
    from hairjax._geometry._shadows import shadow_setup

    pts = np.array([[0.2, 1.0, 0.3], [0.2, 0.0, 0.3], [0.2, -1.0, 0.3]])
    segs = np.array([[0, 1], [1, 2]])
    setup = shadow_setup(pts, segs, np.zeros(2, int), np.ones(1), hj.Light(direction=(0.0, -1.0, 0.0)),
                         hj.Shadows("exact", resolution=16))
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
def test_guard_rasteriser_padding_columns(dtype):
    """_raster._candidates: padding columns (all zeros: L = 0, depths 0) divide by the
    guards' 1 instead of 0 — every output finite, coverage 0 — next to a real column."""
    from hairjax._geometry._raster import _candidates

    with precision(dtype):
        real = [2.2, 3.5, 5.7, 0.0, 5.7, 1.0, 2.0, 3.0, 2.0, 1.0, 1.0]  # x0 y0 dx dy L w z0 z1 k xm reach
        columns = np.zeros((8, 11))
        columns[0] = real
        pixel, cov, t, depth = (np.asarray(o) for o in _candidates(columns, 4, 16, 16, True))
        assert np.all(np.isfinite(cov)) and np.all(np.isfinite(t)) and np.all(np.isfinite(depth))
        np.testing.assert_array_equal(cov[4:], 0.0)  # rows of the padding columns
        assert cov[:4].max() == 1.0  # pixel (2, 3): the line runs through its centre


@pytest.mark.parametrize("dtype", ["float64", "float32"])
def test_guard_constant_depth_fragments_keep_z(dtype):
    """_raster._candidates's za == zb guard (and GLSL fragment_depth's): a segment at one
    depth gives every fragment exactly that depth, although the perspective formula
    1/((1 − t)/z + t/z) rounds away from z (checked here, the guard's reason)."""
    from hairjax._geometry._raster import rasterize

    z = 1.469  # 1/(1/z) ≠ z in float64 and float32
    with precision(dtype):
        frags = rasterize(np.array([[1.2, 3.3]]), np.array([[14.7, 9.1]]), np.array([z]), np.array([z]),
                          np.ones(1), 16, 16, True)
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
        assert (hit.all() if hits == "all" else 0 < hit.sum() < hit.size)
        assert np.all(depth[hit] > 0)
        np.testing.assert_allclose(np.linalg.norm(point[hit], axis=1), 0.5, rtol=1e-12)
        np.testing.assert_allclose(normal[hit], point[hit] / 0.5, atol=1e-12)
    scene = hj.Scene(hj.Strands.from_list([[[2.0, 2.0, 0.0]]]), camera=hj.Camera(width=16, height=16),
                     light=hj.Light(direction=(0.0, 0.0, 1.0)), occluder=occ, shadows=hj.Shadows("none"))
    setup = hj.prepare(scene)
    assert setup.opaque.any() and np.all(setup.occluder_direct == 0.0)  # lit from behind


def test_guard_point_light_on_the_occluder(gl):
    """A point light exactly on the sphere at the centre pixel's hit point: JAX's _unit
    gives L = 0 there (Lambert 0), occluder_color.frag's guarded normalisation too: both
    must show the ambient part k·ambient only, finite."""
    from hairjax.gl import render_gl

    hair = hj.Strands.from_list([[[-0.5, 1.5, 0.5], [0.5, 1.5, 0.5]]], alpha=0.5)
    scene = hj.Scene(hair, camera=hj.Camera(eye=(0.0, 0.0, 4.0), width=9, height=9),
                     light=hj.Light(kind="point", position=(0.0, 0.0, 1.0)),
                     occluder=hj.Occluder(center=(0.0, 0.0, 0.0), radius=1.0, color=(1.0, 1.0, 1.0)),
                     shadows=hj.Shadows("none"))
    assert np.array_equal(hj.prepare(scene).view.pixel_rays()[1][4 * 9 + 4], [0.0, 0.0, -1.0])
    jax_image, gl_image = np.asarray(hj.render(scene)), render_gl(scene).image
    assert np.all(np.isfinite(gl_image))
    amb = np.asarray(scene.params.ambient, np.float64) * np.ones(3)  # k = 1
    np.testing.assert_array_equal(jax_image[4, 4], [*amb, 1.0])
    np.testing.assert_allclose(gl_image[4, 4], [*amb, 1.0], rtol=1e-7)
    np.testing.assert_allclose(gl_image, jax_image, rtol=0, atol=1e-6)


def test_guard_fur_sources():
    """_sources: a normal draw of exactly 0 (a stub generator) gives the direction +y;
    a step where gravity + inertia cancel the direction keeps the direction."""
    from hairjax._scene._procedural import _grow, _unit_vectors

    class Zeros:
        def normal(self, size):
            return np.zeros(size)

    np.testing.assert_array_equal(_unit_vectors(Zeros(), 2), [[0.0, 1.0, 0.0]] * 2)
    out = _grow(np.zeros((1, 3)), np.array([[0.0, 1.0, 0.0]]), np.array([0.5]), 3,
                (0.0, -1.0, 0.0), (0.0, 0.0, 0.0))
    np.testing.assert_array_equal(out[0], [[0.0, 0.0, 0.0], [0.0, 0.5, 0.0], [0.0, 1.0, 0.0]])



# --- random scenes -----------------------------------------------------------------------------

@st.composite
def random_scenes(draw):
    """A small random scene within the issue's ranges, as keyword arguments (the scene is
    built inside the drawn precision): fur ball, camera anywhere (inside the fur ball
    below distance ~1.2), directional or point light (possibly inside), opacity 1e-6 … 1,
    width 0.25 … 8, shininess 0.5 … 1e4, κ 0 … 1e3, all scaled by 1e-4, 1 or 1e4."""
    unit = st.tuples(*[st.floats(-1.0, 1.0)] * 3).filter(lambda v: np.linalg.norm(v) > 0.1)
    return dict(
        dtype=draw(st.sampled_from(["float64", "float32"])),
        hair=dict(strands=draw(st.integers(1, 12)), points=draw(st.integers(2, 5)),
                  seed=draw(st.integers(0, 2**16)), alpha=10.0 ** draw(st.floats(-6.0, 0.0)),
                  # widths on a log grid: the rasteriser compiles once per ribbon reach
                  width=draw(st.sampled_from([0.25, 0.5, 1.0, 2.0, 4.0, 8.0]))),
        scale=10.0 ** draw(st.sampled_from([-4, 0, 4])),
        eye=np.asarray(draw(unit)), distance=draw(st.floats(0.3, 6.0)), fov=draw(st.floats(20.0, 120.0)),
        light=draw(st.one_of(st.tuples(st.just("directional"), unit),
                             st.tuples(st.just("point"), st.tuples(*[st.floats(-1.5, 1.5)] * 3)))),
        shadows=draw(st.sampled_from(["none", "opacity-maps", "exact"])), maps=draw(st.integers(1, 6)),
        model=draw(st.sampled_from(["kajiya-kay", "kajiya-kay-mirror"])),
        params=dict(kd=draw(st.floats(0.0, 1.0)), ks=draw(st.floats(0.0, 1.0)),
                    ambient=draw(st.floats(0.0, 1.0)),
                    shininess=10.0 ** draw(st.floats(np.log10(0.5), 4.0)),
                    kappa=draw(st.one_of(st.just(0.0), st.floats(-3.0, 3.0).map(lambda e: 10.0**e)))),
    )


def build_random_scene(spec) -> hj.Scene:
    s = spec["scale"]
    eye = spec["eye"] / np.linalg.norm(spec["eye"]) * spec["distance"]
    up = (0.0, 1.0, 0.0) if abs(eye[1]) < 0.95 * np.linalg.norm(eye) else (1.0, 0.0, 0.0)
    kind, v = spec["light"]
    light = (hj.Light(direction=v) if kind == "directional"
             else hj.Light(kind="point", position=tuple(s * np.asarray(v))))
    return hj.Scene(hj.furball(**spec["hair"]).transformed(s),
                    camera=hj.Camera(eye=tuple(s * eye), target=(0.0, 0.0, 0.0), up=up, fov=spec["fov"],
                                     width=SIZE, height=SIZE),
                    light=light,
                    shading=hj.shading_model_class(spec["model"])(hj.ShadingParams(**spec["params"])),
                    shadows=shadow_method(spec["shadows"], spec["maps"], SIZE))


# Each example compiles its own scene (~1 s): few examples, no deadline.
@given(spec=random_scenes())
@settings(max_examples=5, deadline=None, suppress_health_check=[HealthCheck.too_slow])
def test_random_scenes(spec):
    """Random scenes: finite image and gradients (shading parameters and opacity), pixels
    within the model's maximum."""
    with precision(spec["dtype"]):
        scene = build_random_scene(spec)
        run = Runner(scene)
        res = run(scene.params)
    assert np.all(np.isfinite(res.image)) and res.image.dtype == np.dtype(spec["dtype"])
    assert finite((res.g_params, res.g_alpha)) and np.all(np.isfinite(res.colors))
    assert_in_bounds(res.image, scene, scene.params, np.dtype(spec["dtype"]))
