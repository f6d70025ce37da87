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
from .._shadows import LightFrame, light_frame, point_planes, with_receivers
from ._buffers import Points, Strands
from ._context import check, get_context, release
from ._occluder import OccluderLight, OccluderSurface, occluder_shadow
from ._programs import programs, workgroups
from ._shading import lookup_texture, shading_uniforms, streak_texture, use_shading_textures
from ._uniforms import light_pass_uniforms, light_uniforms, set_uniforms, vec, view_uniforms

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
                    omega_all = _opacity_maps(ctx, progs, scene, strands, frame, clip_slices, points)
                else:
                    omega_all = _exact_opacity(ctx, progs, scene, strands, frame, points)
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


def _opacity_maps(ctx, progs, scene, strands, frame: LightFrame, clip_slices: bool, points: Points):
    """kim-2003 Routine 2: B_current accumulates slice after slice (GL_ONE, GL_ONE), the
    points of slice i are evaluated between B_prev = Ω(D_i) and B_current = Ω(D_{i+1})."""
    import moderngl

    n, r = scene.shadows.maps, scene.shadows.resolution
    segs = strands.segments[frame.drawable]
    ids = frame.drawable
    # Which slices each drawable segment's fragments can fall in (depth is monotone
    # between the endpoints, so its range is the endpoints' range).
    z = frame.depth
    u0 = np.clip(np.floor(frame.slice_coordinate(np.minimum(z[segs[:, 0]], z[segs[:, 1]]), n)), 0, n)
    u1 = np.clip(np.floor(frame.slice_coordinate(np.maximum(z[segs[:, 0]], z[segs[:, 1]]), n)), 0, n)
    # The clips fire at D_N (slice N, drawn in no pass: such a segment gets no span) and by rounding.
    u0, u1 = u0.astype(np.int64), np.minimum(u1.astype(np.int64), n - 1)
    if clip_slices:
        spans = np.maximum(u1 - u0 + 1, 0)
        seg_rep = np.repeat(ids, spans)
        within = np.arange(spans.sum()) - np.repeat(np.cumsum(spans) - spans, spans)
        slice_rep = np.repeat(u0, spans) + within
        order = np.argsort(slice_rep, kind="stable")
        seg_rep, slice_rep = seg_rep[order], slice_rep[order]
        starts = np.searchsorted(slice_rep, np.arange(n + 1))
    else:
        seg_rep = ids
        starts = None
    ibo = strands.index_buffer(seg_rep)

    plane, _ = point_planes(frame, n)
    seen = np.flatnonzero(frame.seen)
    by_plane = seen[np.argsort(plane[seen], kind="stable")]
    plane_starts = np.searchsorted(plane[by_plane], np.arange(n + 1))
    id_buf = ctx.buffer(by_plane.astype("u4").tobytes() if by_plane.size else b"\0" * 4)  # no point seen
    omega_buf = ctx.buffer(np.zeros(points.count, "f4").tobytes())

    current = ctx.texture((r, r), 1, dtype="f4")
    previous = ctx.texture((r, r), 1, dtype="f4")
    for tex in (current, previous):
        tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
    fbo = ctx.framebuffer(color_attachments=[current])
    prev_fbo = ctx.framebuffer(color_attachments=[previous])
    prog, comp = progs["light_slice"], progs["omega_maps"]
    vao = strands.vertex_array(prog, ibo)
    try:
        fbo.use()
        ctx.viewport = (0, 0, r, r)
        fbo.clear(0.0, 0.0, 0.0, 0.0)
        ctx.disable(moderngl.DEPTH_TEST)
        ctx.enable(moderngl.BLEND)
        ctx.blend_func = moderngl.ONE, moderngl.ONE
        set_uniforms(prog, zmin=float(frame.zmin), span=float(frame.span), maps=n,
                     **light_pass_uniforms(scene, frame))
        set_uniforms(comp, zmin=float(frame.zmin), span=float(frame.span), maps=n, resolution=r,
                     prev_map=0, cur_map=1, **view_uniforms("light", frame.view))
        points.buffer.bind_to_storage_buffer(0)
        id_buf.bind_to_storage_buffer(1)
        omega_buf.bind_to_storage_buffer(2)
        drawn_since_copy = True
        for i in range(n):
            if drawn_since_copy:  # B_prev = Ω(D_i); unchanged if slice i − 1 drew nothing
                ctx.copy_framebuffer(prev_fbo, fbo)
                drawn_since_copy = False
            fbo.use()
            set_uniforms(prog, slice=i)
            if clip_slices:
                count = starts[i + 1] - starts[i]
                if count:
                    vao.render(moderngl.LINES, vertices=2 * int(count), first=2 * int(starts[i]))
                    drawn_since_copy = True
            elif len(seg_rep):
                vao.render(moderngl.LINES, vertices=2 * len(seg_rep))
                drawn_since_copy = True
            count = int(plane_starts[i + 1] - plane_starts[i])
            if count:
                previous.use(0)
                current.use(1)
                set_uniforms(comp, first=int(plane_starts[i]), count=count, plane=i)
                comp.run(group_x=workgroups(count))
                ctx.memory_barrier()
        check(ctx, f"{n} opacity-map passes")
        return np.frombuffer(omega_buf.read(), dtype="f4").copy()
    finally:
        ctx.disable(moderngl.BLEND)
        release(ctx, vao, ibo, id_buf, omega_buf, fbo, prev_fbo, current, previous)


def _exact_opacity(ctx, progs, scene, strands, frame: LightFrame, points: Points):
    """Ω without slicing: per-texel fragment lists (count, prefix sum, fill), then each
    point sums the alpha strictly nearer the light in its 3 × 3 texels."""
    import moderngl

    r = scene.shadows.resolution
    ibo = strands.index_buffer(frame.drawable)
    target = ctx.texture((r, r), 1, dtype="f4")  # the passes write only to buffers
    fbo = ctx.framebuffer(color_attachments=[target])
    counts = ctx.buffer(np.zeros(r * r, "u4").tobytes())
    cursor = ctx.buffer(np.zeros(r * r, "u4").tobytes())
    prog = progs["light_list"]
    vao = strands.vertex_array(prog, ibo)
    buffers = [ibo, target, fbo, counts, cursor, vao]
    try:
        fbo.use()
        ctx.viewport = (0, 0, r, r)
        ctx.disable(moderngl.DEPTH_TEST | moderngl.BLEND)
        set_uniforms(prog, fill=False, **light_pass_uniforms(scene, frame))
        counts.bind_to_storage_buffer(0)
        cursor.bind_to_storage_buffer(1)
        check(ctx, "exact opacity set-up")
        draw = 2 * len(frame.drawable)
        if draw:
            vao.render(moderngl.LINES, vertices=draw)
        ctx.memory_barrier()
        check(ctx, "exact opacity: count pass")
        n_per_texel = np.frombuffer(counts.read(), dtype="u4")
        offsets_np = (np.cumsum(n_per_texel) - n_per_texel).astype("u4")
        total = int(n_per_texel.sum())
        offsets = ctx.buffer(offsets_np.tobytes())
        entries = ctx.buffer(reserve=max(8 * total, 8))  # fires without light-space fragments
        buffers += [offsets, entries]
        offsets.bind_to_storage_buffer(2)
        entries.bind_to_storage_buffer(3)
        set_uniforms(prog, fill=True)
        if draw:
            vao.render(moderngl.LINES, vertices=draw)
        ctx.memory_barrier()
        check(ctx, "exact opacity: fill pass")
        seen = np.flatnonzero(frame.seen).astype("u4")
        ids = ctx.buffer(seen.tobytes() if seen.size else b"\0" * 4)  # fires when no point is seen
        omega_buf = ctx.buffer(np.zeros(points.count, "f4").tobytes())
        buffers += [ids, omega_buf]
        comp = progs["omega_exact"]
        points.buffer.bind_to_storage_buffer(0)
        ids.bind_to_storage_buffer(1)
        omega_buf.bind_to_storage_buffer(2)
        counts.bind_to_storage_buffer(3)
        offsets.bind_to_storage_buffer(4)
        entries.bind_to_storage_buffer(5)
        set_uniforms(comp, count=len(seen), resolution=r, **view_uniforms("light", frame.view))
        if len(seen):
            comp.run(group_x=workgroups(len(seen)))
        ctx.memory_barrier()
        check(ctx, "exact opacity passes")
        return np.frombuffer(omega_buf.read(), dtype="f4").copy()
    finally:
        release(ctx, *buffers)
