"""Ω by deep opacity maps (docs/model.md §7; Yuksel & Keyser 2008, "Deep Opacity Maps"):
a depth pass from the light gives each texel's first hair depth z₀, layer passes add each
fragment's alpha to the boundaries behind its layer, four boundaries to an RGBA target,
and a compute pass reads each point's Ω between the two boundaries around it (lookup
"layer"), or adds, pass by pass, each of its 3 × 3 texels' value at its depth behind that
texel's z₀ (lookup "depth")."""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from .._geometry._shadows import DeepOpacityMaps, LightFrame
from .._scene._scene import Scene
from ._buffers import Points, Strands
from ._context import check, release
from ._programs import workgroups
from ._ribbons import Ribbons
from ._shadow_passes import PassDrawing, register_gl_shadow_pass
from ._uniforms import light_pass_uniforms, set_uniforms, view_uniforms

__all__ = ["deep_opacity_maps"]

# Boundaries per RGBA32F target: one per channel.
BOUNDARIES_PER_TARGET = 4


@register_gl_shadow_pass("deep")
def deep_opacity_maps(
    ctx, progs, scene: Scene, strands: Strands, frame: LightFrame, points: Points, drawing: PassDrawing
) -> np.ndarray:
    """z₀ by MIN blending; then for each group of four boundaries (1 … K and the total,
    K + 1), the layers drawn additively into one RGBA target and the points whose upper
    boundary is in the group evaluated between it and the group before. (Layers follow
    each texel's z₀, not global depth slices: `drawing.clip_slices` does not apply.)"""
    import moderngl

    shadows = scene.shadows
    if not isinstance(shadows, DeepOpacityMaps):  # the pass registered for it: never fires
        raise TypeError(f"the deep pass got shadows.method = {shadows.method!r}")
    k, r = shadows.layers, shadows.resolution
    ibo = strands.index_buffer(frame.drawable)
    seen = np.flatnonzero(frame.seen).astype("u4")
    ids = ctx.buffer(seen.tobytes() if seen.size else b"\0" * 4)  # fires when no point is seen
    omega_buf = ctx.buffer(np.zeros(points.count, "f4").tobytes())
    maps = _DeepBuffers.make(ctx, r)
    comp = progs["omega_deep"]
    screen = strands.screen_buffer(frame)
    segments = len(frame.drawable)
    first = Ribbons(ctx, progs, "deep_first", strands, ibo, segments, drawing.expansion, screen)
    layer = Ribbons(ctx, progs, "deep_layers", strands, ibo, segments, drawing.expansion, screen)
    depth_range = float(shadows.depth_range(frame))
    try:
        ctx.viewport = (0, 0, r, r)
        ctx.disable(moderngl.DEPTH_TEST)
        ctx.enable(moderngl.BLEND)
        _depth_pass(ctx, maps, first, light_pass_uniforms(scene, frame))
        ctx.blend_equation = moderngl.FUNC_ADD
        ctx.blend_func = moderngl.ONE, moderngl.ONE
        maps.first.use(0)
        layer.set_uniforms(
            first_map=0, layers=k, depth_range=depth_range, **light_pass_uniforms(scene, frame)
        )
        set_uniforms(
            comp,
            first_map=0,
            prev_map=1,
            cur_map=2,
            layers=k,
            depth_range=depth_range,
            resolution=r,
            count=len(seen),
            depth_lookup=shadows.lookup == "depth",
            **view_uniforms("light", frame.view),
        )
        points.buffer.bind_to_storage_buffer(0)
        ids.bind_to_storage_buffer(1)
        omega_buf.bind_to_storage_buffer(2)
        groups = -(-(k + 1) // BOUNDARIES_PER_TARGET)  # ⌈(K + 1)/4⌉
        _layer_passes(ctx, maps, layer, comp, len(seen), groups)
        # The compute passes' Ω stores, before the read below. Nothing between the passes
        # reads them, and GL orders a pass's texture reads before the next pass's
        # writes to the targets: no barrier per pass.
        ctx.memory_barrier()
        check(ctx, f"deep opacity maps: {groups} layer passes")
        return np.frombuffer(omega_buf.read(), dtype="f4").copy()
    finally:
        ctx.blend_equation = moderngl.FUNC_ADD
        ctx.disable(moderngl.BLEND)
        release(
            ctx,
            first,
            layer,
            screen,
            ibo,
            ids,
            omega_buf,
            maps.first_fbo,
            *maps.fbos,
            maps.first,
            *maps.targets,
        )


class _DeepBuffers(NamedTuple):
    """`first`: each texel's z₀ (one float); `targets`: two RGBA targets of four boundaries
    each, the current group's and the one before, alternating; `r × r` texels, read texel
    by texel (nearest); and their framebuffers."""

    first: Any
    targets: list[Any]
    first_fbo: Any
    fbos: list[Any]

    @classmethod
    def make(cls, ctx, r: int) -> _DeepBuffers:
        import moderngl

        first = ctx.texture((r, r), 1, dtype="f4")
        targets = [ctx.texture((r, r), 4, dtype="f4") for _ in range(2)]
        for tex in (first, *targets):
            tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
        first_fbo = ctx.framebuffer(color_attachments=[first])
        fbos = [ctx.framebuffer(color_attachments=[t]) for t in targets]
        fbos[1].clear(0.0, 0.0, 0.0, 0.0)  # group 0's "group before": read, never used
        return cls(first, targets, first_fbo, fbos)


def _depth_pass(ctx, maps: _DeepBuffers, ribbons: Ribbons, uniforms: dict) -> None:
    """z₀: the nearest fragment per texel, by MIN blending; +∞ stays where no hair is."""
    import moderngl

    maps.first_fbo.use()
    maps.first_fbo.clear(float("inf"), 0.0, 0.0, 0.0)
    ctx.blend_equation = moderngl.MIN
    ribbons.set_uniforms(**uniforms)
    ribbons.draw()
    check(ctx, "deep opacity maps: depth pass")


def _layer_passes(ctx, maps: _DeepBuffers, ribbons: Ribbons, comp, seen: int, groups: int) -> None:
    """Per group of four boundaries: the layers drawn additively into the group's target,
    then Ω of the `seen` points whose upper boundary is in the group, between it and the
    group before."""

    for g in range(groups):
        cur, prev = g % 2, (g + 1) % 2  # the group before is in the other target
        maps.fbos[cur].use()
        maps.fbos[cur].clear(0.0, 0.0, 0.0, 0.0)
        ribbons.set_uniforms(group=g)
        ribbons.draw()
        if seen:
            maps.first.use(0)
            maps.targets[prev].use(1)
            maps.targets[cur].use(2)
            set_uniforms(comp, group=g)
            comp.run(group_x=workgroups(seen))
