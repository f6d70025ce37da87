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

from .._render import tangents, visibility_order
from .._scene import Scene
from .._scheuermann import ScheuermannParams, scheuermann_inputs
from .._shading import ShadingParams
from .._shadows import LightFrame, light_frame, point_planes
from ._context import check, get_context, release
from ._programs import SHADING_MODEL_IDS, programs

__all__ = ["GLResult", "render_gl"]

_GROUP = 64  # local size of the compute shaders


@dataclasses.dataclass(frozen=True)
class GLResult:
    """`image`: `float32[H, W, 4]` linear RGBA, row 0 at the top; `omega`: Ω per point
    (`float32[P]`, None without shadows); `timings`: seconds by pass."""

    image: np.ndarray
    omega: np.ndarray | None
    timings: dict


def _set(prog, **values) -> None:
    """Set uniforms; names the compiler removed as unused are skipped."""
    for name, value in values.items():
        try:
            uniform = prog[name]
        except KeyError:
            continue
        uniform.value = value


def _vec(v) -> tuple:
    """A vector as the tuple of Python floats a moderngl uniform takes."""
    return tuple(float(x) for x in np.asarray(v).ravel())


def _view_uniforms(prefix: str, view) -> dict:
    return {f"{prefix}.origin": _vec(view.origin), f"{prefix}.forward": _vec(view.forward),
            f"{prefix}.right": _vec(view.right), f"{prefix}.up": _vec(view.up),
            f"{prefix}.focal": float(view.focal), f"{prefix}.center": (float(view.cx), float(view.cy)),
            # Fires for orthographic (directional-light) views: near = −inf, unused there.
            f"{prefix}.near": float(view.near) if np.isfinite(view.near) else -1e30,
            f"{prefix}.perspective": bool(view.perspective)}


class _Strands:
    """The strands on the GPU: one buffer per point attribute, shared by every pass."""

    def __init__(self, ctx, scene: Scene):
        s = scene.strands
        per_point = s.strand_of_point
        self.ctx = ctx
        self.count = s.num_points
        f4 = lambda a: ctx.buffer(np.ascontiguousarray(a, dtype="f4").tobytes())  # noqa: E731
        tangent = tangents(s.points, s.offsets)
        color = s.color if s.color is not None else np.ones_like(s.points)
        alpha = s.alpha[per_point]
        self.segments = s.segments()
        self.extra = []  # §13's per-point inputs: Scheuermann scenes only
        if scene.shading_model == "scheuermann":
            pts, factor, segment_alpha = scheuermann_inputs(s, tangent, scene.scheuermann_maps)
            color = color * factor
            if segment_alpha is not None:
                # ribbon.geom takes a segment's alpha from its first point.
                alpha = alpha.copy()
                alpha[self.segments[:, 0]] *= segment_alpha
            self.extra = [(f4(pts.normal), "3f", "in_normal"),
                          (f4(np.stack([pts.shift, pts.mask], axis=1)), "2f", "in_maps")]
        self.position = f4(s.points)
        self.tangent = f4(tangent)
        self.color = f4(color)
        self.alpha = f4(alpha)
        self.width = f4(s.width[per_point])
        self.omega = f4(np.zeros(s.num_points))

    def vertex_array(self, prog, index_buffer):
        return self.ctx.vertex_array(prog, [
            (self.position, "3f", "in_position"), (self.tangent, "3f", "in_tangent"),
            (self.color, "3f", "in_color"), (self.alpha, "f", "in_alpha"),
            (self.width, "f", "in_width"), (self.omega, "f", "in_omega"), *self.extra,
        ], index_buffer=index_buffer, index_element_size=4, skip_errors=True)

    def index_buffer(self, segment_ids: np.ndarray):
        """Endpoints of the given segments, in order, for GL_LINES."""
        pairs = self.segments[segment_ids].astype("u4")
        return self.ctx.buffer(pairs.tobytes() if pairs.size else b"\0" * 8)  # no segments: GL needs ≥ 1 byte

    def release(self):
        for b in (self.position, self.tangent, self.color, self.alpha, self.width, self.omega,
                  *(buffer for buffer, _, _ in self.extra)):
            b.release()


def render_gl(scene: Scene, params: ShadingParams | ScheuermannParams | None = None, *,
              clip_slices: bool = True, omega: np.ndarray | None = None,
              order: np.ndarray | None = None) -> GLResult:
    """Render `scene` with OpenGL.

    **Arguments:** `params` (default `scene.params`); `clip_slices`: draw into each
    opacity map only the segments whose depth range meets its slice (kim-2003 §4.2); off
    draws all of them into every map (the basic algorithm) — the same image, for timing;
    `omega`: use this Ω per point (`[P]`) instead of computing the shadows; `order`: draw
    the camera pass in this segment order instead of sorting (`visibility_order`, e.g. an
    order reused from an earlier view).
    """
    params = scene.params if params is None else params
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

    strands = _Strands(ctx, scene)
    try:
        lap("upload")
        if omega is not None:
            omega = np.asarray(omega, dtype="f4").reshape(strands.count)
            strands.omega.write(omega.tobytes())
        elif scene.shadows.method != "none":
            frame = light_frame(scene.strands.points, strands.segments, scene.strands.width,
                                scene.light, scene.shadows.resolution)
            if scene.shadows.method == "opacity-maps":
                omega = _opacity_maps(ctx, progs, scene, strands, frame, clip_slices)
            else:
                omega = _exact_opacity(ctx, progs, scene, strands, frame)
            lap("shadows")
        image = _camera_pass(ctx, progs, scene, params, strands, order)
        lap("camera pass")
        return GLResult(image, omega, timings)
    finally:
        strands.release()


def _light_uniforms(scene: Scene) -> dict:
    light = scene.light
    if light.kind == "directional":
        d = -np.asarray(light.direction, dtype=np.float64)
        vector, point = d / np.linalg.norm(d), False
    else:
        vector, point = np.asarray(light.position, dtype=np.float64), True
    return {"light_vector": _vec(vector), "point_light": point,
            "light_rgb": _vec(light.color)}


def _camera_pass(ctx, progs, scene: Scene, params, strands, order=None) -> np.ndarray:
    import moderngl

    cam = scene.camera
    w, h = cam.width, cam.height
    view, _, depth, _, order = visibility_order(scene, order)
    # Depths map to [0, 1) for the depth test: anything drawn lies in (near, depth_far).
    # No floor at 1 unit (was initial=1.0): depth/far is stored in 2⁻²⁴ steps, tiny scenes lost digits.
    depth_far = 2.0 * float(max(np.max(depth, initial=0.0), cam.near))
    if scene.occluder is not None:
        c = np.asarray(scene.occluder.center) - view.origin
        depth_far = max(depth_far, 2.0 * (float(c @ view.forward) + scene.occluder.radius))
    color = ctx.texture((w, h), 4, dtype="f4")
    depth_tex = ctx.depth_texture((w, h))
    fbo = ctx.framebuffer(color_attachments=[color], depth_attachment=depth_tex)
    ibo = strands.index_buffer(order)
    try:
        fbo.use()
        ctx.viewport = (0, 0, w, h)
        bg = _vec(scene.background)
        fbo.clear(*bg, 0.0, depth=1.0)
        common = dict(raster_size=(float(w), float(h)), depth_far=depth_far,
                      **_view_uniforms("view", view), **_light_uniforms(scene))
        if scene.occluder is not None:
            ctx.disable(moderngl.BLEND)
            ctx.enable(moderngl.DEPTH_TEST)
            ctx.depth_func = "<"
            fbo.depth_mask = True
            occ = scene.occluder
            _set(progs["sphere"], center=_vec(occ.center), radius=float(occ.radius),
                 albedo=_vec(occ.color), **common)
            sphere_vao = ctx.vertex_array(progs["sphere"], [])
            sphere_vao.render(moderngl.TRIANGLES, vertices=3)
            sphere_vao.release()
            check(ctx, "occluder pass")
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
        _set(prog, shade=True, eye=_vec(view.origin), **_shading_uniforms(scene, params), **common)
        vao = strands.vertex_array(prog, ibo)
        if len(order):
            vao.render(moderngl.LINES, vertices=2 * len(order))
        vao.release()
        check(ctx, "camera pass")
        data = np.frombuffer(color.read(), dtype="f4").reshape(h, w, 4)
        return data[::-1].copy()  # GL's row 0 is the bottom
    finally:
        ctx.disable(moderngl.BLEND | moderngl.DEPTH_TEST)
        release(ctx, ibo, fbo, color, depth_tex)


def _shading_uniforms(scene: Scene, params) -> dict:
    """The `shading` (and for §13 the `scheuermann`) uniforms of the camera pass."""
    uniforms = {"shading.model": SHADING_MODEL_IDS[scene.shading_model],
                "shading.kappa": float(params.kappa)}
    if scene.shading_model == "scheuermann":
        if not isinstance(params, ScheuermannParams):
            raise TypeError("shading model 'scheuermann' takes ScheuermannParams, "
                            f"got {type(params).__name__}")
        for name in ("kd", "ambient", "primary_color", "secondary_color"):
            uniforms[f"scheuermann.{name}"] = _vec(getattr(params, name))
        for name in ("primary_exponent", "secondary_exponent", "primary_shift", "secondary_shift"):
            uniforms[f"scheuermann.{name}"] = float(getattr(params, name))
        return uniforms
    return {**uniforms, "shading.kd": _vec(params.kd), "shading.ks": _vec(params.ks),
            "shading.ambient": _vec(params.ambient), "shading.shininess": float(params.shininess)}


def _light_pass_uniforms(scene: Scene, frame: LightFrame) -> dict:
    r = scene.shadows.resolution
    return dict(raster_size=(float(r), float(r)), shade=False,
                light_perspective=bool(frame.view.perspective), resolution=r,
                **_view_uniforms("view", frame.view))


def _opacity_maps(ctx, progs, scene, strands, frame: LightFrame, clip_slices: bool):
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
    omega_buf = ctx.buffer(np.zeros(strands.count, "f4").tobytes())

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
        _set(prog, zmin=float(frame.zmin), span=float(frame.span), maps=n,
             **_light_pass_uniforms(scene, frame))
        _set(comp, zmin=float(frame.zmin), span=float(frame.span), maps=n, resolution=r,
             prev_map=0, cur_map=1, **_view_uniforms("light", frame.view))
        strands.position.bind_to_storage_buffer(0)
        id_buf.bind_to_storage_buffer(1)
        omega_buf.bind_to_storage_buffer(2)
        drawn_since_copy = True
        for i in range(n):
            if drawn_since_copy:  # B_prev = Ω(D_i); unchanged if slice i − 1 drew nothing
                ctx.copy_framebuffer(prev_fbo, fbo)
                drawn_since_copy = False
            fbo.use()
            _set(prog, slice=i)
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
                _set(comp, first=int(plane_starts[i]), count=count, plane=i)
                comp.run(group_x=(count + _GROUP - 1) // _GROUP)
                ctx.memory_barrier()
        check(ctx, f"{n} opacity-map passes")
        omega = np.frombuffer(omega_buf.read(), dtype="f4").copy()
        strands.omega.write(omega.tobytes())
        return omega
    finally:
        ctx.disable(moderngl.BLEND)
        release(ctx, vao, ibo, id_buf, omega_buf, fbo, prev_fbo, current, previous)


def _exact_opacity(ctx, progs, scene, strands, frame: LightFrame):
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
        _set(prog, fill=False, **_light_pass_uniforms(scene, frame))
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
        _set(prog, fill=True)
        if draw:
            vao.render(moderngl.LINES, vertices=draw)
        ctx.memory_barrier()
        check(ctx, "exact opacity: fill pass")
        seen = np.flatnonzero(frame.seen).astype("u4")
        ids = ctx.buffer(seen.tobytes() if seen.size else b"\0" * 4)  # fires when no point is seen
        omega_buf = ctx.buffer(np.zeros(strands.count, "f4").tobytes())
        buffers += [ids, omega_buf]
        comp = progs["omega_exact"]
        strands.position.bind_to_storage_buffer(0)
        ids.bind_to_storage_buffer(1)
        omega_buf.bind_to_storage_buffer(2)
        counts.bind_to_storage_buffer(3)
        offsets.bind_to_storage_buffer(4)
        entries.bind_to_storage_buffer(5)
        _set(comp, count=len(seen), resolution=r, **_view_uniforms("light", frame.view))
        if len(seen):
            comp.run(group_x=(len(seen) + _GROUP - 1) // _GROUP)
        ctx.memory_barrier()
        check(ctx, "exact opacity passes")
        omega = np.frombuffer(omega_buf.read(), dtype="f4").copy()
        strands.omega.write(omega.tobytes())
        return omega
    finally:
        release(ctx, *buffers)
