"""Ω by opacity shadow maps (docs/model.md §7; kim-2003 §4, Routine 2): the hair drawn
from the light slice after slice into additive buffers, each point's Ω read between the
maps that bound its slice."""

from __future__ import annotations

import numpy as np

from .._geometry._shadows import LightFrame, OpacityMaps, point_planes
from .._scene._scene import Scene
from ._buffers import Points, Strands
from ._context import check, release
from ._programs import workgroups
from ._shadow_passes import register_gl_shadow_pass
from ._uniforms import light_pass_uniforms, set_uniforms, view_uniforms

__all__ = ["opacity_maps"]


@register_gl_shadow_pass("opacity-maps")
def opacity_maps(
    ctx, progs, scene: Scene, strands: Strands, frame: LightFrame, points: Points, *, clip_slices: bool = True
) -> np.ndarray:
    """kim-2003 Routine 2: B_current accumulates slice after slice (GL_ONE, GL_ONE), the
    points of slice i are evaluated between B_prev = Ω(D_i) and B_current = Ω(D_{i+1})."""
    import moderngl

    shadows = scene.shadows
    if not isinstance(shadows, OpacityMaps):  # the pass registered for it: never fires
        raise TypeError(f"the opacity-maps pass got shadows.method = {shadows.method!r}")
    n, r = shadows.maps, shadows.resolution
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
        set_uniforms(
            prog, zmin=float(frame.zmin), span=float(frame.span), maps=n, **light_pass_uniforms(scene, frame)
        )
        set_uniforms(
            comp,
            zmin=float(frame.zmin),
            span=float(frame.span),
            maps=n,
            resolution=r,
            prev_map=0,
            cur_map=1,
            **view_uniforms("light", frame.view),
        )
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
            if starts is not None:  # clip_slices
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
