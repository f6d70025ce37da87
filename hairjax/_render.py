"""The staged renderer: scene → geometry stage → shading stage → image (docs/model.md).

- `prepare(scene)`: NumPy set-up that depends on geometry, camera and light only:
  projection, visibility order, fragments, occluder test, the opacity-map gather plan
  (for strand points and the occluder's surface points), the occluder's shadow.
  Cached per `Scene` object.
- `geometry_stage(scene, alpha)`: the opacity-dependent JAX part: compositing weights
  and Ω. Differentiable in the per-strand `alpha`.
- `shading_stage(geometry, params)`: Kajiya-Kay at the points, τ = exp(−κΩ), the
  occluder's colour (τ at its surface, docs/model.md §13), and the weighted sum that is
  the composite. Differentiable in `ShadingParams`.

A scene without shadows builds no shadow work; a scene without occluder runs no occluder
test. Re-rendering with new parameters reuses both earlier stages.
"""

from __future__ import annotations

import dataclasses
import time
import weakref

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ._composite import over_weights
from ._lookup import LOOKUP_MODELS, kajiya_kay_lookup
from ._occluder import occluder_hits, occluder_light_view, occluder_visibility, sphere_hits
from ._ordering import draw_order, hair_centre, segment_depth, stable_argsort_uint32, static_order
from ._projection import View, camera_view
from ._raster import rasterize, ribbon_widths
from ._scene import Scene
from ._scheuermann import ScheuermannParams, ScheuermannPoints, scheuermann, scheuermann_inputs
from ._shading import ShadingParams, kajiya_kay
from ._shadows import ShadowSetup, exact_opacity, opacity_maps, point_opacity, shadow_setup
from ._streaks import strand_coordinates, streak_factor, streak_prefix, streak_texture

__all__ = ["Setup", "Geometry", "prepare", "visibility_order", "sphere_hits", "to_light",
           "geometry_stage", "shading_stage", "composite", "point_colors", "occluder_colors", "render",
           "render_profiled", "forget", "tangents"]


def tangents(points: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Unit tangents: central differences, one-sided at strand ends (`float64[P, 3]`).

    Zero where the difference is zero (repeated points, one-point strands): such a point
    reflects ambient light only.
    """
    prev = np.arange(len(points)) - 1
    nxt = np.arange(len(points)) + 1
    starts, ends = offsets[:-1], offsets[1:] - 1
    prev[starts] = starts
    nxt[ends] = ends
    # _unit gives 0 for repeated points and one-point strands: the tangent does not exist.
    return _unit(points[nxt] - points[prev])


def _unit(v: np.ndarray) -> np.ndarray:
    norm = np.linalg.norm(v, axis=-1, keepdims=True)
    # Fires for zero vectors (a repeated point's tangent, a point light or the eye at a
    # strand point): no direction, so no light.
    return np.where(norm > 0, v / np.where(norm > 0, norm, 1.0), 0.0)


@dataclasses.dataclass(frozen=True)
class Setup:
    """Geometry set-up: everything that depends on neither opacity nor shading parameters."""

    view: View
    tangent: np.ndarray          # [P, 3]
    to_light: np.ndarray         # [P, 3]
    to_eye: np.ndarray           # [P, 3]
    base_color: np.ndarray       # [P, 3] per-point colour (ones when the hair has none)
    light_rgb: np.ndarray        # [3]
    # Camera fragments, sorted by pixel, front to back within a pixel:
    frag_pixel: np.ndarray       # [F]
    frag_i0: np.ndarray          # [F] first point of the fragment's segment (the second is i0 + 1)
    frag_t: np.ndarray           # [F] screen-space position along the segment
    frag_strand: np.ndarray      # [F]
    frag_coverage: np.ndarray    # [F]
    frag_first: np.ndarray       # [F] first fragment of its pixel
    frag_last: np.ndarray        # [F] last fragment of its pixel
    backdrop: np.ndarray         # [H*W, 3] the background behind the hair (0 on the occluder)
    opaque: np.ndarray           # [H*W] the occluder covers the pixel centre
    shadow: ShadowSetup | None   # with an occluder and shadows, its points follow the strands'
    timings: dict
    # The occluder (§9, §13); None without one:
    occluder_pixel: np.ndarray | None = None    # [Q] the pixels it covers
    occluder_direct: np.ndarray | None = None   # [Q, 3] k·light·max(N·L, 0) at them
    occluder_visibility: np.ndarray | None = None  # [Q] V there: 0 where it shadows itself
    occluder_color: np.ndarray | None = None    # [3] k
    light_visibility: np.ndarray | None = None  # [P] V: 0 where the occluder shadows a strand point
    scheuermann: ScheuermannPoints | None = None  # NumPy; Scheuermann scenes only (§17)


class Geometry(eqx.Module):
    """Output of the geometry stage: what the shading stage needs, as JAX arrays."""

    tangent: Float[Array, "P 3"]
    to_light: Float[Array, "P 3"]
    to_eye: Float[Array, "P 3"]
    base_color: Float[Array, "P 3"]
    light_rgb: Float[Array, 3]
    omega: Float[Array, " P"] | None
    light_visibility: Float[Array, " P"] | None
    occluder_pixel: Array | None
    occluder_direct: Float[Array, "Q 3"] | None
    occluder_color: Float[Array, " 3"] | None
    occluder_omega: Float[Array, " Q"] | None
    occluder_visibility: Float[Array, " Q"] | None
    frag_pixel: Array
    frag_i0: Array  # the segment's first point; its second is frag_i0 + 1
    frag_t: Float[Array, " F"]
    frag_weight: Float[Array, " F"]
    frag_alpha: Float[Array, " F"]
    transmittance: Float[Array, " HW"]
    backdrop: Float[Array, "HW 3"]
    alpha_channel: Float[Array, " HW"]
    height: int = eqx.field(static=True)
    width: int = eqx.field(static=True)
    model: str = eqx.field(static=True)
    lookup_size: int = eqx.field(static=True, default=0)  # lookup models' table size (§14)
    streak: Float[Array, " P"] | None = None  # §16's factor per point; None without streaks
    scheuermann: ScheuermannPoints | None = None  # Scheuermann scenes only (§17)


_SETUP_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def prepare(scene: Scene, *, order=None) -> Setup:
    """The NumPy geometry set-up of `scene`, cached per scene object.

    `order`: a draw order to use instead of the scene's (see `visibility_order`); such a
    set-up is computed afresh, not cached."""
    if order is not None:
        with jax.ensure_compile_time_eval():
            return _prepare(scene, order)
    cached = _SETUP_CACHE.get(scene)
    if cached is None:
        # The set-up depends on concrete geometry only: evaluate it eagerly even when
        # `render` is being traced (e.g. under jax.jit or jax.grad).
        with jax.ensure_compile_time_eval():
            cached = _prepare(scene)
        _SETUP_CACHE[scene] = cached
    return cached


def visibility_order(scene: Scene, order=None):
    """Camera projection and the segments' draw order (docs/model.md §2, §4), shared by
    the JAX and GL renderers.

    Returns `(view, xy [P, 2], depth [P], segments [E, 2], order)`; `order` lists the
    drawable segments (both ends beyond the near plane), the first drawn first.

    `order` (optional): segment indices, the first drawn first, to use instead of sorting
    for this camera — e.g. an order computed for an earlier view and reused (kim-2003 §3,
    Fig. 8). Segments in it that are not drawable from this camera are skipped; segments
    not in it are not drawn. Indices must be distinct and in [0, E).
    """
    cam = scene.camera
    view = camera_view(cam)
    xy, depth = view.project(scene.strands.points)
    segments = scene.strands.segments()
    # Segments with an end nearer than the near plane (or behind the eye) are not drawn.
    drawable_mask = (depth[segments[:, 0]] > cam.near) & (depth[segments[:, 1]] > cam.near)
    if order is not None:
        order = _given_order(order, len(segments))
        return view, xy, depth, segments, order[drawable_mask[order]]
    if scene.ordering.method == "static":  # the same for every view: no depths needed
        order = static_order(scene.strands.points, segments,
                             hair_centre(scene.strands.points, scene.strands.offsets))
        return view, xy, depth, segments, order[drawable_mask[order]]
    drawable = np.flatnonzero(drawable_mask)
    order = drawable[draw_order(segment_depth(depth, segments[drawable]),
                                scene.ordering.method, scene.ordering.bins)]
    return view, xy, depth, segments, order


def _given_order(order, n_segments: int) -> np.ndarray:
    """`order` checked: a 1-D array of distinct segment indices in [0, n_segments)."""
    order = np.asarray(order)
    if order.ndim != 1 or (order.size and not np.issubdtype(order.dtype, np.integer)):
        raise ValueError(f"order must be a 1-D array of segment indices, got shape {order.shape} "
                         f"and dtype {order.dtype}")
    order = order.astype(np.int64)
    if order.size and (order.min() < 0 or order.max() >= n_segments):
        raise ValueError(f"order has segment indices outside [0, {n_segments})")
    if order.size and np.bincount(order, minlength=n_segments).max() > 1:
        raise ValueError("order lists a segment more than once")
    return order


def _prepare(scene: Scene, order=None) -> Setup:
    timings = {}
    clock = time.perf_counter()

    def lap(name):
        nonlocal clock
        now = time.perf_counter()
        timings[name] = now - clock
        clock = now

    strands, cam = scene.strands, scene.camera
    points = strands.points
    view, xy, depth, segments, order = visibility_order(scene, order)
    seg_strand = strands.strand_of_point[segments[:, 0]]
    lap("project+order")

    tangent = tangents(points, strands.offsets)
    base_color = strands.color if strands.color is not None else np.ones_like(points)
    extra, segment_alpha = None, None
    if scene.shading_model == "scheuermann":  # §17's per-point inputs: this model only
        extra, factor, segment_alpha = scheuermann_inputs(strands, tangent, scene.scheuermann_maps)
        base_color = base_color * factor
        lap("scheuermann inputs")

    # Rasterise nearest-first, then a stable sort by pixel gives front-to-back per pixel.
    near_first = order[::-1]
    s0, s1 = segments[near_first, 0], segments[near_first, 1]
    widths = ribbon_widths(strands.width[seg_strand[near_first]], strands.width_units, depth[s0],
                           depth[s1], view.focal, view.perspective)
    frags = rasterize(xy[s0], xy[s1], depth[s0], depth[s1], widths, cam.width, cam.height, True)
    lap("rasterize")

    hw = cam.width * cam.height
    light = scene.light
    light_rgb = np.asarray(light.color, dtype=np.float64)
    backdrop = np.broadcast_to(np.asarray(scene.background, np.float64), (hw, 3)).copy()
    opaque = np.zeros(hw, bool)
    occluder = {}
    if scene.occluder is not None:
        hit_depth, normal, hit_point = occluder_hits(view, scene.occluder)
        opaque = np.isfinite(hit_depth)
        occ_pixel = np.flatnonzero(opaque)
        surface = hit_point[occ_pixel]
        to_l = to_light(light, surface)
        # Lambert's max(N·L, 0) (§9): the clip fires on the occluder's unlit side.
        lambert = np.clip(np.sum(normal[occ_pixel] * to_l, axis=1), 0.0, None)
        color = np.asarray(scene.occluder.color, np.float64)
        occluder = dict(occluder_pixel=occ_pixel, occluder_color=color,
                        occluder_direct=color * light_rgb * lambert[:, None])
        backdrop[opaque] = 0.0  # the shading stage adds the occluder's colour (§13)
        # kim-2003 §3: depth test on, hair does not write depth.
        visible = np.flatnonzero(frags.depth < hit_depth[frags.pixel])
        frags = frags.take(visible)
        lap("occluder")

    # Only what compositing needs is permuted: pixel, segment, coverage, t (not depth).
    sort = stable_argsort_uint32(frags.pixel)
    pixel, frag_coverage, frag_t = frags.pixel[sort], frags.coverage[sort], frags.t[sort]
    seg = near_first[frags.segment[sort]]
    if segment_alpha is not None:  # §17's alpha texture scales the segment's opacity
        frag_coverage = frag_coverage * segment_alpha[seg]
    del frags
    first = np.ones(pixel.size, bool)
    first[1:] = pixel[1:] != pixel[:-1]
    last = np.ones(pixel.size, bool)
    last[:-1] = first[1:]
    lap("sort fragments")

    shadow = None
    if scene.shadows.method != "none":
        receivers = surface if occluder else None
        shadow = shadow_setup(points, segments, seg_strand, strands.width, light,
                              scene.shadows.method, scene.shadows.maps, scene.shadows.resolution,
                              receivers=receivers, segment_alpha=segment_alpha,
                              width_units=strands.width_units)
        lap("shadow set-up")
        if occluder:
            # §13: the occluder's shadow, a depth test in the light's view.
            light_view = occluder_light_view(light, points, scene.occluder,
                                             scene.shadows.resolution)
            depth_map, _, _ = occluder_hits(light_view, scene.occluder)
            occluder["light_visibility"] = occluder_visibility(light_view, depth_map, points)
            occluder["occluder_visibility"] = occluder_visibility(light_view, depth_map, surface)
            lap("occluder shadow")

    return Setup(
        view=view, tangent=tangent, to_light=to_light(light, points),
        to_eye=_unit(view.origin - points), base_color=base_color, light_rgb=light_rgb,
        frag_pixel=pixel, frag_i0=segments[seg, 0].astype(np.int32), frag_t=frag_t,
        frag_strand=seg_strand[seg].astype(np.int32), frag_coverage=frag_coverage,
        frag_first=first, frag_last=last, backdrop=backdrop, opaque=opaque, shadow=shadow,
        timings=timings, scheuermann=extra, **occluder,
    )


def to_light(light, points: np.ndarray) -> np.ndarray:
    if light.kind == "directional":
        d = -np.asarray(light.direction, dtype=np.float64)
        return np.broadcast_to(d / np.linalg.norm(d), points.shape)
    return _unit(np.asarray(light.position, dtype=np.float64) - points)


@eqx.filter_jit
def _composite_weights(alpha, frag_strand, frag_coverage, frag_first, frag_last, last_pixel,
                       opaque):
    frag_alpha = alpha[frag_strand] * frag_coverage
    weights, inclusive = over_weights(frag_alpha, frag_first, frag_last)
    # Pixels without fragments keep T = 1; each covered pixel's last fragment sets its T
    # (`last_pixel` points every other fragment past the end, where it is dropped).
    transmittance = jnp.ones(opaque.shape[0], weights.dtype).at[last_pixel].set(
        inclusive, mode="drop")
    alpha_channel = 1.0 - transmittance * (1.0 - opaque)
    return weights, frag_alpha, transmittance, alpha_channel


@eqx.filter_jit
def _map_opacity(alpha, frag_strand, frag_coverage, frag_cell, plane, f, texel, maps, resolution):
    omega = opacity_maps(alpha[frag_strand] * frag_coverage, frag_cell, maps, resolution)
    return point_opacity(omega, plane, f, texel)


@eqx.filter_jit
def _exact_opacity(alpha, frag_strand, frag_coverage, frag_first, index, weight):
    return exact_opacity(alpha[frag_strand] * frag_coverage, frag_first, index, weight)


def _omega(scene: Scene, shadow: ShadowSetup, alpha, dtype):
    coverage = jnp.asarray(shadow.frag_coverage, dtype)
    if shadow.method == "opacity-maps":
        return _map_opacity(alpha, shadow.frag_strand, coverage, shadow.frag_cell, shadow.plane,
                            jnp.asarray(shadow.f, dtype), shadow.texel, scene.shadows.maps,
                            scene.shadows.resolution)
    return _exact_opacity(alpha, shadow.frag_strand, coverage, shadow.frag_first, shadow.index,
                          jnp.asarray(shadow.weight, dtype))


_GEOMETRY_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def geometry_stage(scene: Scene, alpha: Float[Array, " S"] | None = None, *,
                   order=None) -> Geometry:
    """Compositing weights and Ω for `scene`, differentiable in the per-strand `alpha`.

    **Arguments:** `scene`; `alpha` (`[S]`, default the scene's strand opacities) — may be
    a traced JAX array, e.g. under `jax.grad`. With the default, the result is computed
    once per scene (eagerly, even under a trace) and cached. `order`: a draw order to use
    instead of the scene's (`visibility_order`); then nothing is cached.
    """
    if order is not None:
        if alpha is None:
            with jax.ensure_compile_time_eval():
                return _geometry_stage(scene, scene.strands.alpha, order)
        return _geometry_stage(scene, alpha, order)
    if alpha is None:
        cached = _GEOMETRY_CACHE.get(scene)
        if cached is None:
            with jax.ensure_compile_time_eval():
                cached = _geometry_stage(scene, scene.strands.alpha)
            _GEOMETRY_CACHE[scene] = cached
        return cached
    return _geometry_stage(scene, alpha)


def _geometry_stage(scene: Scene, alpha, order=None) -> Geometry:
    setup = prepare(scene, order=order)
    dtype = jnp.result_type(float)
    alpha = jnp.asarray(alpha, dtype=dtype)
    hw = scene.camera.width * scene.camera.height
    last_pixel = np.where(setup.frag_last, setup.frag_pixel, hw)
    weights, frag_alpha, transmittance, alpha_channel = _composite_weights(
        alpha, setup.frag_strand, jnp.asarray(setup.frag_coverage, dtype), setup.frag_first,
        setup.frag_last, last_pixel, jnp.asarray(setup.opaque, dtype))
    omega = occluder_omega = None
    if setup.shadow is not None:
        omega = _omega(scene, setup.shadow, alpha, dtype)
        if setup.occluder_pixel is not None:
            # The occluder's surface points follow the strand points (§13).
            p = scene.strands.num_points
            omega, occluder_omega = omega[:p], omega[p:]
    maybe = lambda x, t=dtype: None if x is None else jnp.asarray(x, t)  # noqa: E731
    return Geometry(
        tangent=jnp.asarray(setup.tangent, dtype), to_light=jnp.asarray(setup.to_light, dtype),
        to_eye=jnp.asarray(setup.to_eye, dtype), base_color=jnp.asarray(setup.base_color, dtype),
        light_rgb=jnp.asarray(setup.light_rgb, dtype), omega=omega,
        light_visibility=maybe(setup.light_visibility),
        occluder_pixel=maybe(setup.occluder_pixel, jnp.int32),
        occluder_direct=maybe(setup.occluder_direct), occluder_color=maybe(setup.occluder_color),
        occluder_omega=occluder_omega, occluder_visibility=maybe(setup.occluder_visibility),
        frag_pixel=jnp.asarray(setup.frag_pixel, jnp.int32),
        frag_i0=jnp.asarray(setup.frag_i0, jnp.int32),
        frag_t=jnp.asarray(setup.frag_t, dtype), frag_weight=weights, frag_alpha=frag_alpha,
        transmittance=transmittance, backdrop=jnp.asarray(setup.backdrop, dtype),
        alpha_channel=alpha_channel, height=scene.camera.height, width=scene.camera.width,
        model=scene.shading_model, lookup_size=scene.lookup_size,
        streak=None if scene.streaks is None else _streak_factors(scene, dtype),
        scheuermann=None if setup.scheuermann is None else jax.tree.map(
            lambda x: jnp.asarray(x, dtype), setup.scheuermann),
    )


def _streak_factors(scene: Scene, dtype) -> Float[Array, " P"]:
    """§16: each point's streak factor, the texture's mean over its hair's [u_i, u_i + Δ]."""
    streaks, strands = scene.streaks, scene.strands
    texture = streak_texture(streaks)
    u = strand_coordinates(streaks, strands.num_strands)[strands.strand_of_point]
    return jax.vmap(streak_factor, in_axes=(None, None, 0, None))(
        jnp.asarray(texture, dtype), jnp.asarray(streak_prefix(texture), dtype),
        jnp.asarray(u, dtype), streaks.width)


def point_colors(geometry: Geometry, params: ShadingParams | ScheuermannParams) -> Float[Array, "P 3"]:
    """Shaded colour at every strand point (Gouraud, kim-2003 §5):
    ambient·c + τ·V · light · (Kd·sin(T, L)·c + Ks·spec), with c the per-point colour;
    for the Scheuermann model (§17) c · (ambient + τ·V · light · (diffuse + specular));
    either times the streak factor (§16)."""
    if geometry.model == "scheuermann":
        colors = _scheuermann_colors(geometry, params)
    else:
        if not isinstance(params, ShadingParams):
            raise TypeError(f"shading model {geometry.model!r} takes ShadingParams, "
                            f"got {type(params).__name__}")
        if geometry.model in LOOKUP_MODELS:  # §14: the same terms read from a table
            diffuse, specular = kajiya_kay_lookup(geometry.tangent, geometry.to_light,
                                                  geometry.to_eye, params, geometry.lookup_size,
                                                  geometry.model)
        else:
            diffuse, specular = jax.vmap(kajiya_kay, in_axes=(0, 0, 0, None, None))(
                geometry.tangent, geometry.to_light, geometry.to_eye, params, geometry.model)
        lit = geometry.light_rgb[None, :] * (diffuse * geometry.base_color + specular)
        colors = params.ambient[None, :] * geometry.base_color + _shadowed(geometry, lit, params.kappa)
    if geometry.streak is not None:  # §16: the streak texture modulates the whole colour
        colors = colors * geometry.streak[:, None]
    return colors


def _shadowed(geometry: Geometry, lit: Float[Array, "P 3"], kappa) -> Float[Array, "P 3"]:
    """The direct light at the points times τ = exp(−κΩ) (§7) and the occluder's V (§13)."""
    if geometry.omega is not None:
        lit = lit * jnp.exp(-kappa * geometry.omega)[:, None]
    if geometry.light_visibility is not None:
        lit = lit * geometry.light_visibility[:, None]
    return lit


def occluder_colors(geometry: Geometry, params: ShadingParams) -> Float[Array, "Q 3"]:
    """The occluder's colour at the pixels it covers (docs/model.md §13):
    k·ambient + τ·k·light·max(N·L, 0)·V, τ = exp(−κΩ) at its surface point."""
    direct = geometry.occluder_direct
    if geometry.occluder_omega is not None:
        direct = direct * jnp.exp(-params.kappa * geometry.occluder_omega)[:, None]
    if geometry.occluder_visibility is not None:
        direct = direct * geometry.occluder_visibility[:, None]
    return params.ambient[None, :] * geometry.occluder_color[None, :] + direct


def _scheuermann_colors(geometry: Geometry, params: ScheuermannParams) -> Float[Array, "P 3"]:
    if not isinstance(params, ScheuermannParams):
        raise TypeError(f"shading model 'scheuermann' takes ScheuermannParams, got {type(params).__name__}")
    pts = geometry.scheuermann
    diffuse, specular = jax.vmap(scheuermann, in_axes=(0, 0, 0, 0, 0, 0, None))(
        geometry.tangent, pts.normal, geometry.to_light, geometry.to_eye, pts.shift, pts.mask, params)
    lit = geometry.light_rgb[None, :] * (diffuse + specular)
    return geometry.base_color * (params.ambient[None, :] + _shadowed(geometry, lit, params.kappa))


def composite(geometry: Geometry, colors: Float[Array, "P C"]) -> Float[Array, "HW C"]:
    """Σ_k w_k ((1 − t_k) c(p₀) + t_k c(p₁)) per pixel: the hair's part of the composite
    (docs/model.md §6), linear in the point colours. The backdrop term is not included."""
    t = geometry.frag_t[:, None]
    frag_color = (1 - t) * colors[geometry.frag_i0] + t * colors[geometry.frag_i0 + 1]
    hw = geometry.height * geometry.width
    return jax.ops.segment_sum(geometry.frag_weight[:, None] * frag_color, geometry.frag_pixel,
                               num_segments=hw, indices_are_sorted=True)


@eqx.filter_jit
def shading_stage(geometry: Geometry, params: ShadingParams) -> Float[Array, "H W 4"]:
    """The image from the geometry stage and the shading parameters (`[H, W, 4]`)."""
    rgb = composite(geometry, point_colors(geometry, params))
    backdrop = geometry.backdrop
    if geometry.occluder_pixel is not None:
        backdrop = backdrop.at[geometry.occluder_pixel].set(occluder_colors(geometry, params))
    rgb = rgb + geometry.transmittance[:, None] * backdrop
    image = jnp.concatenate([rgb, geometry.alpha_channel[:, None]], axis=1)
    return image.reshape(geometry.height, geometry.width, 4)


def render(scene: Scene, params: ShadingParams | None = None,
           alpha: Float[Array, " S"] | None = None, *, order=None) -> Float[Array, "H W 4"]:
    """Render `scene` to linear RGBA `[H, W, 4]`.

    Differentiable in `params` (default `scene.params`) and in the per-strand `alpha`
    (default the scene's); jit-able with the scene closed over:
    `jax.jit(lambda p: render(scene, p))` (the geometry then enters the compiled function
    as constants; for repeated calls, `shading_stage(geometry_stage(scene), p)` passes it
    as arguments instead). With the default `alpha`, both earlier stages are cached per
    scene, so a new `params` re-runs only the shading stage. `order`: segment indices to
    draw in, instead of sorting for this camera (e.g. an order reused from an earlier
    view, kim-2003 Fig. 8; see `visibility_order`); the earlier stages then run afresh.
    """
    params = scene.params if params is None else params
    if scene.patches is not None:  # §18: hair patches, drawn with slide 17's four passes
        if alpha is not None or order is not None:
            raise ValueError("a hair-patch scene takes neither `alpha` nor `order`")
        from ._patches import render_patches

        return render_patches(scene, params)
    return shading_stage(geometry_stage(scene, alpha, order=order), params)


def forget(scene: Scene) -> None:
    """Drop `scene`'s cached set-up and geometry stage, so the next render runs them all
    again (for timing a full render)."""
    _SETUP_CACHE.pop(scene, None)
    _GEOMETRY_CACHE.pop(scene, None)


def render_profiled(scene: Scene, params: ShadingParams | None = None):
    """Render and time each stage (block-until-ready between stages).

    Returns `(image, timings)`; timings are seconds by stage name, set-up sub-steps
    prefixed with `geometry/`. Includes compilation on a first call.
    """
    params = scene.params if params is None else params
    if scene.patches is not None:  # §18: one stage, the patches' set-up and composite
        t0 = time.perf_counter()
        image = jax.block_until_ready(render(scene, params))
        return image, {"patches (four passes)": time.perf_counter() - t0,
                       "total": time.perf_counter() - t0}
    forget(scene)
    t0 = time.perf_counter()
    setup = prepare(scene)
    t1 = time.perf_counter()
    geometry = jax.block_until_ready(geometry_stage(scene))
    t2 = time.perf_counter()
    image = jax.block_until_ready(shading_stage(geometry, params))
    t3 = time.perf_counter()
    timings = {f"geometry/{k}": v for k, v in setup.timings.items()}
    timings["geometry set-up (NumPy)"] = t1 - t0
    timings["geometry opacity (JAX)"] = t2 - t1
    timings["shading"] = t3 - t2
    timings["total"] = t3 - t0
    return image, timings
