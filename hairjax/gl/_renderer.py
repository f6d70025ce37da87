"""The GL renderer: docs/model.md on OpenGL through moderngl.

Same inputs as the JAX renderer and the same NumPy code for what is not per-pixel maths:
the camera's draw order (`visibility_order`), the light's frame (`light_frame`), each
point's plane (`point_planes`) and the tangents. Everything per pixel or per texel runs in
shaders: ribbons and coverage, Kajiya-Kay at points, the opacity maps (kim-2003 Routine 2:
two buffers, additive slices, Ω per slice of points) or the exact Ω from per-texel fragment
lists, the occluder and the far-to-near "over" blending.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from .._occluder import drawable_triangles
from .._projection import View, camera_view
from .._render import visibility_order
from .._scene import Scene
from .._scheuermann import ScheuermannParams
from .._shading import ShadingParams
from .._shadows import light_frame, with_receivers
from ._buffers import Points, Strands
from ._context import check, get_context, release
from ._exact_opacity import exact_opacity
from ._occluder import OccluderLight, OccluderSurface, occluder_shadow
from ._opacity_maps import opacity_maps
from ._programs import programs
from ._shading import lookup_texture, shading_uniforms, streak_texture, use_shading_textures
from ._uniforms import light_uniforms, set_uniforms, vec, view_uniforms

__all__ = ["GLResult", "render_gl"]


@dataclasses.dataclass(frozen=True)
class GLResult:
    """`image`: `float32[H, W, 4]` linear RGBA, row 0 at the top; `omega`: Ω per point
    (`float32[P]`, None without shadows); `timings`: seconds by pass; `occluder`: the
    occluder's part of the light (None without occluder or shadows)."""

    image: np.ndarray
    omega: np.ndarray | None
    timings: dict
    occluder: OccluderLight | None = None


def render_gl(scene: Scene, params: ShadingParams | ScheuermannParams | None = None, *,
              clip_slices: bool = True, omega: np.ndarray | None = None,
              order: np.ndarray | None = None, occluder: OccluderLight | None = None) -> GLResult:
    """Render `scene` with OpenGL.

    **Arguments:** `params` (default `scene.params`); `clip_slices`: draw into each
    opacity map only the segments whose depth range meets its slice (kim-2003 §4.2); off
    draws all of them into every map (the basic algorithm) — the same image, for timing;
    `omega`: use this Ω per point (`[P]`) instead of computing the shadows; `order`: draw
    the camera pass in this segment order instead of sorting (`visibility_order`, e.g. an
    order reused from an earlier view); `occluder`: with `omega`, the occluder's part of
    the light to use (`occluder_light(scene, geometry)` gives the JAX renderer's); required
    with `omega` when the scene has an occluder and shadows.
    """
    params = scene.params if params is None else params
    if scene.patches is not None:
        return _render_patches(scene, params, omega, order, occluder)
    ctx = get_context()
    progs = programs(ctx)
    timings = {}
    clock = time.perf_counter()

    def lap(name):
        nonlocal clock
        ctx.finish()
        now = time.perf_counter()
        timings[name] = timings.get(name, 0.0) + now - clock
        clock = now

    view, _, depth, _, order = visibility_order(scene, order)
    depth_far = _depth_far(scene, view, depth)
    lighting = scene.occluder is not None and scene.shadows.method != "none"
    strands = Strands(ctx, scene)
    surface = None
    try:
        lap("upload")
        if scene.occluder is not None:
            surface = OccluderSurface(ctx, progs, scene.occluder, view, (0.0, depth_far))
            lap("occluder surface")
        if omega is not None:
            omega = np.asarray(omega, dtype="f4").reshape(strands.count)
            strands.omega.write(omega.tobytes())
            if lighting and occluder is None:
                raise ValueError("render_gl: with omega and a scene whose occluder takes part in "
                                 "the light, pass occluder= too (occluder_light(scene, geometry))")
        elif scene.shadows.method != "none":
            frame = light_frame(scene.strands.points, strands.segments, scene.strands.width,
                                scene.light, scene.shadows.resolution, scene.strands.width_units)
            points = Points(ctx, strands, None if surface is None else surface.points)
            try:
                frame = with_receivers(frame, points.receivers)
                if scene.shadows.method == "opacity-maps":
                    omega_all = opacity_maps(ctx, progs, scene, strands, frame, clip_slices, points)
                else:
                    omega_all = exact_opacity(ctx, progs, scene, strands, frame, points)
                omega = omega_all[:strands.count].copy()
                strands.omega.write(omega.tobytes())
                lap("shadows")
                if lighting:
                    occluder = occluder_shadow(ctx, progs, scene, strands, points, surface,
                                               omega_all[strands.count:])
                    lap("occluder shadow")
            finally:
                points.release()
        if lighting:
            strands.visibility.write(np.asarray(occluder.visibility, "f4").tobytes())
        image = _camera_pass(ctx, progs, scene, params, strands, view, order, depth_far, surface,
                             occluder if lighting else None)
        lap("camera pass")
        return GLResult(image, omega, timings, occluder if lighting else None)
    finally:
        strands.release()
        if surface is not None:
            surface.release()


def _render_patches(scene: Scene, params, omega, order, occluder) -> GLResult:
    """docs/model.md §18: slide 17's four passes in GL over the patch mesh. The per-point
    colours come from the JAX shading (`scene_point_colors`): GL here checks visibility
    and compositing, not the shading (the ribbon path checks that)."""
    from .._patches import scene_patches, scene_point_colors
    from ._patches import render_patches_gl

    if omega is not None or order is not None or occluder is not None:
        raise ValueError("a hair-patch scene takes none of `omega`, `order`, `occluder`")
    clock = time.perf_counter()
    colors = np.asarray(scene_point_colors(scene, params), np.float64)
    shaded = time.perf_counter()
    image = render_patches_gl(get_context(), camera_view(scene.camera), scene_patches(scene),
                              colors, scene.background)
    timings = {"point colours (JAX)": shaded - clock, "four passes": time.perf_counter() - shaded}
    return GLResult(image, None, timings)


def _depth_far(scene: Scene, view: View, depth: np.ndarray) -> float:
    """The camera depth mapped to 1 in the depth buffer: anything drawn lies in (near, far)."""
    cam = scene.camera
    # No floor at 1 unit (was initial=1.0): depth/far is stored in 2⁻²⁴ steps, tiny scenes lost digits.
    far = 2.0 * float(max(np.max(depth, initial=0.0), cam.near))
    occ = scene.occluder
    if occ is not None and occ.kind == "sphere":
        c = np.asarray(occ.center) - view.origin
        far = max(far, 2.0 * (float(c @ view.forward) + occ.radius))
    elif occ is not None:
        drawn = occ.triangles[drawable_triangles(view, occ.vertices, occ.triangles)]
        if drawn.size:  # fires unless every triangle reaches the near plane
            far = max(far, 2.0 * float(np.max((occ.vertices[drawn] - view.origin) @ view.forward)))
    return far


def _camera_pass(ctx, progs, scene: Scene, params, strands, view: View, order,
                 depth_far: float, surface: OccluderSurface | None,
                 occluder: OccluderLight | None) -> np.ndarray:
    import moderngl

    cam = scene.camera
    w, h = cam.width, cam.height
    color = ctx.texture((w, h), 4, dtype="f4")
    # Depths map to [0, 1) for the depth test: anything drawn lies in (near, depth_far); the
    # occluder's surface pass already wrote its depths.
    own_depth = ctx.depth_texture((w, h)) if surface is None else None
    depth_tex = own_depth if surface is None else surface.depth
    fbo = ctx.framebuffer(color_attachments=[color], depth_attachment=depth_tex)
    ibo = strands.index_buffer(order)
    extra = []
    table = lookup_texture(ctx, scene, params)
    streak = streak_texture(ctx, scene)
    try:
        fbo.use()
        ctx.viewport = (0, 0, w, h)
        bg = vec(scene.background)
        fbo.depth_mask = surface is None  # keep the occluder's depths
        fbo.clear(*bg, 0.0, depth=1.0)
        common = dict(raster_size=(float(w), float(h)), depth_far=depth_far,
                      world_width=scene.strands.width_units == "world",
                      **view_uniforms("view", view), **light_uniforms(scene))
        if surface is not None:
            # §13: the occluder's colour where its surface pass covered the pixel centre.
            ctx.disable(moderngl.BLEND | moderngl.DEPTH_TEST)
            fbo.depth_mask = False
            if occluder is None:
                omega_img = np.zeros((h, w), "f4")
                vis_img = np.ones((h, w), "f4")
            else:  # the per-pixel arrays have row 0 at the top, textures at the bottom
                omega_img = np.ascontiguousarray(occluder.omega[::-1], "f4")
                vis_img = np.ascontiguousarray(occluder.surface_visibility[::-1], "f4")
            omega_tex = ctx.texture((w, h), 1, omega_img.tobytes(), dtype="f4")
            vis_tex = ctx.texture((w, h), 1, vis_img.tobytes(), dtype="f4")
            extra += [omega_tex, vis_tex]
            prog = progs["occluder_color"]
            for unit, tex in enumerate((surface.position, surface.normal, omega_tex, vis_tex)):
                tex.use(unit)
            set_uniforms(prog, position_map=0, normal_map=1, omega_map=2, visibility_map=3,
                         albedo=vec(scene.occluder.color), ambient=vec(params.ambient),
                         kappa=float(params.kappa), **light_uniforms(scene))
            occ_vao = ctx.vertex_array(prog, [])
            extra.append(occ_vao)
            occ_vao.render(moderngl.TRIANGLES, vertices=3)
            check(ctx, "occluder colour pass")
            ctx.enable(moderngl.DEPTH_TEST)
            ctx.depth_func = "<"
        else:
            ctx.disable(moderngl.DEPTH_TEST)
        # kim-2003 §3: hair far to near, depth test on (if anything wrote depth), no depth
        # writes; "over" for colour, and 1 − Π(1 − α) for alpha.
        fbo.depth_mask = False
        ctx.enable(moderngl.BLEND)
        ctx.blend_func = (moderngl.SRC_ALPHA, moderngl.ONE_MINUS_SRC_ALPHA,
                          moderngl.ONE, moderngl.ONE_MINUS_SRC_ALPHA)
        ctx.blend_equation = moderngl.FUNC_ADD
        prog = progs["camera"]
        set_uniforms(prog, shade=True, eye=vec(view.origin), **shading_uniforms(scene, params), **common)
        use_shading_textures(prog, scene, table, streak)
        vao = strands.vertex_array(prog, ibo)
        if len(order):
            vao.render(moderngl.LINES, vertices=2 * len(order))
        vao.release()
        check(ctx, "camera pass")
        data = np.frombuffer(color.read(), dtype="f4").reshape(h, w, 4)
        return data[::-1].copy()  # GL's row 0 is the bottom
    finally:
        ctx.disable(moderngl.BLEND | moderngl.DEPTH_TEST)
        release(ctx, ibo, fbo, color, *([own_depth] if own_depth is not None else []), *extra, table, streak)
