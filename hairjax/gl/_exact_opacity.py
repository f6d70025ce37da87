"""The exact Ω (docs/model.md §7's `exact` method): no slicing, the alpha of every
fragment strictly nearer the light than a point, from per-texel fragment lists."""

from __future__ import annotations

import numpy as np

from .._geometry._shadows import LightFrame
from .._scene._scene import Scene
from ._buffers import Points, Strands
from ._context import check, release
from ._programs import workgroups
from ._ribbons import Ribbons
from ._shadow_passes import PassDrawing, register_gl_shadow_pass
from ._uniforms import light_pass_uniforms, set_uniforms, view_uniforms

__all__ = ["exact_opacity"]


@register_gl_shadow_pass("exact")
def exact_opacity(
    ctx, progs, scene: Scene, strands: Strands, frame: LightFrame, points: Points, drawing: PassDrawing
) -> np.ndarray:
    """Ω without slicing: per-texel fragment lists (count, prefix sum, fill), then each
    point sums the alpha strictly nearer the light in its 3 × 3 texels. (No slices:
    `drawing.clip_slices` does not apply.)"""
    import moderngl

    r = scene.shadows.resolution
    ibo = strands.index_buffer(frame.drawable)
    target = ctx.texture((r, r), 1, dtype="f4")  # the passes write only to buffers
    fbo = ctx.framebuffer(color_attachments=[target])
    counts = ctx.buffer(np.zeros(r * r, "u4").tobytes())
    cursor = ctx.buffer(np.zeros(r * r, "u4").tobytes())
    screen = strands.screen_buffer(frame)
    ribbons = Ribbons(ctx, progs, "light_list", strands, ibo, len(frame.drawable), drawing.expansion, screen)
    buffers = [ibo, screen, target, fbo, counts, cursor, ribbons]
    try:
        fbo.use()
        ctx.viewport = (0, 0, r, r)
        ctx.disable(moderngl.DEPTH_TEST | moderngl.BLEND)
        ribbons.set_uniforms(fill=False, **light_pass_uniforms(scene, frame))
        counts.bind_to_storage_buffer(0)
        cursor.bind_to_storage_buffer(1)
        check(ctx, "exact opacity set-up")
        ribbons.draw()
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
        ribbons.set_uniforms(fill=True)
        ribbons.draw()
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
