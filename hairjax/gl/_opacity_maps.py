"""Ω by opacity shadow maps (docs/model.md §7; kim-2003 §4, Routine 2): the hair drawn
from the light slice after slice into additive buffers, each point's Ω read between the
maps that bound its slice."""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from .._geometry._shadows import LightFrame, OpacityMaps, point_planes
from .._scene._scene import Scene
from ._buffers import Points, Strands
from ._context import check, release
from ._programs import workgroups
from ._ribbons import Ribbons
from ._shadow_passes import PassDrawing, register_gl_shadow_pass
from ._uniforms import light_pass_uniforms, set_uniforms, view_uniforms

__all__ = ["opacity_maps"]


@register_gl_shadow_pass("opacity-maps")
def opacity_maps(
    ctx, progs, scene: Scene, strands: Strands, frame: LightFrame, points: Points, drawing: PassDrawing
) -> np.ndarray:
    """kim-2003 Routine 2: B_current accumulates slice after slice (GL_ONE, GL_ONE), the
    points of slice i are evaluated between B_prev = Ω(D_i) and B_current = Ω(D_{i+1})."""
    import moderngl

    shadows = scene.shadows
    if not isinstance(shadows, OpacityMaps):  # the pass registered for it: never fires
        raise TypeError(f"the opacity-maps pass got shadows.method = {shadows.method!r}")
    n, r = shadows.maps, shadows.resolution
    draws = _slice_draws(frame, strands.segments, n, drawing.clip_slices)
    ibo = strands.index_buffer(draws.segments)
    slices = _points_by_slice(frame, n)
    id_buf = ctx.buffer(
        slices.points.astype("u4").tobytes() if slices.points.size else b"\0" * 4
    )  # none seen
    omega_buf = ctx.buffer(np.zeros(points.count, "f4").tobytes())
    maps = _MapBuffers.make(ctx, r)
    comp = progs["omega_maps"]
    screen = strands.screen_buffer(frame)
    ribbons = Ribbons(ctx, progs, "light_slice", strands, ibo, len(draws.segments), drawing.expansion, screen)
    try:
        maps.fbo.use()
        ctx.viewport = (0, 0, r, r)
        maps.fbo.clear(0.0, 0.0, 0.0, 0.0)
        ctx.disable(moderngl.DEPTH_TEST)
        ctx.enable(moderngl.BLEND)
        ctx.blend_func = moderngl.ONE, moderngl.ONE
        ribbons.set_uniforms(
            zmin=float(frame.zmin), span=float(frame.span), maps=n, **light_pass_uniforms(scene, frame)
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
        _slice_passes(ctx, ribbons, comp, maps, draws, slices, n)
        # The compute passes' Ω stores, before the read below. Nothing between the passes
        # reads them, and GL orders a pass's texture reads before the next pass's
        # writes to the maps: no barrier per pass.
        ctx.memory_barrier()
        check(ctx, f"{n} opacity-map passes")
        return np.frombuffer(omega_buf.read(), dtype="f4").copy()
    finally:
        ctx.disable(moderngl.BLEND)
        release(
            ctx, ribbons, screen, ibo, id_buf, omega_buf, maps.fbo, maps.prev_fbo, maps.current, maps.previous
        )


class _SliceDraws(NamedTuple):
    """The segments drawn from the light, as index-buffer entries. With `clip_slices`, each
    segment once per slice its depth range meets, by slice: slice i's run is
    `starts[i]:starts[i + 1]`; without, every drawable segment once (`starts` None: all of
    them drawn into every map, kim-2003's basic algorithm)."""

    segments: np.ndarray
    starts: np.ndarray | None


def _slice_draws(frame: LightFrame, segments: np.ndarray, n: int, clip_slices: bool) -> _SliceDraws:
    """Which slices each drawable segment's fragments can fall in (depth is monotone
    between the endpoints, so its range is the endpoints' range): kim-2003 §4.2."""
    ids = frame.drawable
    if not clip_slices:
        return _SliceDraws(ids, None)
    segs = segments[ids]
    z = frame.depth
    u0 = np.clip(np.floor(frame.slice_coordinate(np.minimum(z[segs[:, 0]], z[segs[:, 1]]), n)), 0, n)
    u1 = np.clip(np.floor(frame.slice_coordinate(np.maximum(z[segs[:, 0]], z[segs[:, 1]]), n)), 0, n)
    # The clips fire at D_N (slice N, drawn in no pass: such a segment gets no span) and by rounding.
    u0, u1 = u0.astype(np.int64), np.minimum(u1.astype(np.int64), n - 1)
    spans = np.maximum(u1 - u0 + 1, 0)
    seg_rep = np.repeat(ids, spans)
    within = np.arange(spans.sum()) - np.repeat(np.cumsum(spans) - spans, spans)
    slice_rep = np.repeat(u0, spans) + within
    order = _stable_order(slice_rep, n - 1)
    seg_rep, slice_rep = seg_rep[order], slice_rep[order]
    return _SliceDraws(seg_rep, np.searchsorted(slice_rep, np.arange(n + 1)))


def _stable_order(keys: np.ndarray, top: int) -> np.ndarray:
    """The stable sort's order of integer `keys` in [0, `top`]: as 16-bit keys where they
    fit, which take NumPy's radix sort (8× as fast as int64 keys' merge sort on 3 M
    keys below 64, as the slice entries of 100k strands are)."""
    return np.argsort(keys.astype(np.uint16) if top < 1 << 16 else keys, kind="stable")


class _PointSlices(NamedTuple):
    """The points seen from the light, by the slice their depth falls in (`point_planes`):
    slice i's are `points[starts[i]:starts[i + 1]]`."""

    points: np.ndarray
    starts: np.ndarray


def _points_by_slice(frame: LightFrame, n: int) -> _PointSlices:
    plane, _ = point_planes(frame, n)
    seen = np.flatnonzero(frame.seen)
    by_plane = seen[_stable_order(plane[seen], n - 1)]
    return _PointSlices(by_plane, np.searchsorted(plane[by_plane], np.arange(n + 1)))


class _MapBuffers(NamedTuple):
    """kim-2003 Routine 2's two buffers: B_current, drawn into additively, and B_prev, its
    copy before the slice; `r × r` float texels, read texel by texel (nearest)."""

    current: Any
    previous: Any
    fbo: Any
    prev_fbo: Any

    @classmethod
    def make(cls, ctx, r: int) -> _MapBuffers:
        import moderngl

        current = ctx.texture((r, r), 1, dtype="f4")
        previous = ctx.texture((r, r), 1, dtype="f4")
        for tex in (current, previous):
            tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
        fbo = ctx.framebuffer(color_attachments=[current])
        prev_fbo = ctx.framebuffer(color_attachments=[previous])
        return cls(current, previous, fbo, prev_fbo)


def _slice_passes(
    ctx, ribbons: Ribbons, comp, maps: _MapBuffers, draws: _SliceDraws, slices: _PointSlices, n: int
):
    """For each slice i: B_prev = Ω(D_i), slice i's segments drawn into B_current, which
    then holds Ω(D_{i+1}); and Ω of slice i's points, between the two."""

    drawn_since_copy = True
    for i in range(n):
        if drawn_since_copy:  # B_prev = Ω(D_i); unchanged if slice i − 1 drew nothing
            ctx.copy_framebuffer(maps.prev_fbo, maps.fbo)
            drawn_since_copy = False
        maps.fbo.use()
        ribbons.set_uniforms(slice=i)
        if draws.starts is not None:  # clip_slices
            count = int(draws.starts[i + 1] - draws.starts[i])
            if count:
                ribbons.draw(int(draws.starts[i]), count)
                drawn_since_copy = True
        elif len(draws.segments):
            ribbons.draw()
            drawn_since_copy = True
        count = int(slices.starts[i + 1] - slices.starts[i])
        if count:
            maps.previous.use(0)
            maps.current.use(1)
            set_uniforms(comp, first=int(slices.starts[i]), count=count, plane=i)
            comp.run(group_x=workgroups(count))
