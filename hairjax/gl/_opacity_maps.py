"""Ω by opacity shadow maps (docs/model.md §7, §11; kim-2003 §4, Routine 2): the hair drawn
from the light slice after slice into additive maps, four a pass (kim-2003 §4.1: one map
per colour channel), each point's Ω read between the maps that bound its slice, the
points of a pass's slices in one dispatch."""

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
    """kim-2003 Routine 2, MAPS_PER_PASS maps a pass (§4.1's packing into the colour
    channels): each pass's maps start at the pass before's last, Ω(D_b₀), its slices are
    drawn additively (GL_ONE, GL_ONE) slice after slice into every map behind them, then
    the points of slice i are evaluated between Ω(D_i) and Ω(D_{i+1}). Each map sums the
    same alphas in the same order as one accumulation buffer does: the same Ω, bit for bit."""
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
    plane_buf = ctx.buffer(slices.planes.astype("i4").tobytes() if slices.planes.size else b"\0" * 4)
    omega_buf = ctx.buffer(np.zeros(points.count, "f4").tobytes())
    maps = _MapBuffers.make(ctx, r)
    comp, seed = progs["omega_maps"], progs["light_seed"]
    seed_vao = ctx.vertex_array(seed, [])
    screen = strands.screen_buffer(frame)
    ribbons = Ribbons(ctx, progs, "light_slice", strands, ibo, len(draws.segments), drawing.expansion, screen)
    try:
        ctx.viewport = (0, 0, r, r)
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
        plane_buf.bind_to_storage_buffer(3)
        _slice_passes(ctx, ribbons, (comp, seed_vao), maps, draws, slices, n)
        # The compute passes' Ω stores, before the read below. Nothing between the passes
        # reads them, and GL orders a pass's texture reads before the next pass's
        # writes to the maps: no barrier per pass.
        ctx.memory_barrier()
        check(ctx, f"{n} opacity-map passes")
        return np.frombuffer(omega_buf.read(), dtype="f4").copy()
    finally:
        ctx.disable(moderngl.BLEND)
        release(ctx, ribbons, seed_vao, screen, ibo, id_buf, plane_buf, omega_buf, *maps.fbos, *maps.targets)


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
    planes: np.ndarray
    starts: np.ndarray


def _points_by_slice(frame: LightFrame, n: int) -> _PointSlices:
    plane, _ = point_planes(frame, n)
    seen = np.flatnonzero(frame.seen)
    by_plane = seen[_stable_order(plane[seen], n - 1)]
    planes = plane[by_plane]
    return _PointSlices(by_plane, planes, np.searchsorted(planes, np.arange(n + 1)))


MAPS_PER_PASS = 4  # kim-2003 §4.1: one map per colour channel of an RGBA target


class _MapBuffers(NamedTuple):
    """Two RGBA `r × r` float targets of MAPS_PER_PASS maps each, read texel by texel
    (nearest): pass p draws into `targets[p % 2]` while the other holds the pass before's
    maps (its alpha, Ω of the pass's first plane); and their framebuffers."""

    targets: list[Any]
    fbos: list[Any]

    @classmethod
    def make(cls, ctx, r: int) -> _MapBuffers:
        import moderngl

        targets = [ctx.texture((r, r), 4, dtype="f4") for _ in range(2)]
        for tex in targets:
            tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
        fbos = [ctx.framebuffer(color_attachments=[t]) for t in targets]
        fbos[1].clear(0.0, 0.0, 0.0, 0.0)  # the first pass's "pass before": Ω(D_0) = 0
        return cls(targets, fbos)


def _slice_passes(
    ctx, ribbons: Ribbons, evaluate, maps: _MapBuffers, draws: _SliceDraws, slices: _PointSlices, n: int
):
    """Per pass of MAPS_PER_PASS slices b₀ … b₁ − 1: its maps start at Ω(D_b₀) (the pass
    before's last), each slice's segments are drawn into them in turn, and then Ω of the
    pass's points, each between the maps around its slice."""
    import moderngl

    comp, seed_vao = evaluate
    for p, b0 in enumerate(range(0, n, MAPS_PER_PASS)):
        b1 = min(n, b0 + MAPS_PER_PASS)
        cur, before = p % 2, (p + 1) % 2
        maps.fbos[cur].use()
        maps.fbos[cur].clear(0.0, 0.0, 0.0, 0.0)
        if p:  # 0 + Ω(D_b₀) = Ω(D_b₀) in every channel
            maps.targets[before].use(0)
            seed_vao.render(moderngl.TRIANGLES, vertices=3)
        ribbons.set_uniforms(first_boundary=b0 + 1)
        for i in range(b0, b1):
            ribbons.set_uniforms(slice=i)
            if draws.starts is not None:  # clip_slices
                count = int(draws.starts[i + 1] - draws.starts[i])
                if count:
                    ribbons.draw(int(draws.starts[i]), count)
            elif len(draws.segments):
                ribbons.draw()
        first, count = int(slices.starts[b0]), int(slices.starts[b1] - slices.starts[b0])
        if count:
            maps.targets[before].use(0)
            maps.targets[cur].use(1)
            set_uniforms(comp, first=first, count=count, first_slice=b0)
            comp.run(group_x=workgroups(count))
