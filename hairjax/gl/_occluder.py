"""The occluder in GL (docs/model.md §9, §13; kim-2003 §3's drawing pass and §4's
shadows): its surface drawn into a view's raster, its shadow on the hair and on itself from
the light's view, and `OccluderLight`, the occluder's part of the light."""

from __future__ import annotations

import dataclasses

import numpy as np

from .._geometry._occluder import drawable_triangles, occluder_extent, occluder_light_view, vertex_normals
from .._geometry._projection import View
from .._scene._scene import Scene
from ._buffers import Points, Strands
from ._context import check, release
from ._programs import workgroups
from ._uniforms import light_uniforms, set_uniforms, vec, view_uniforms

__all__ = ["OccluderLight", "OccluderSurface", "draw_occluder_color", "occluder_light", "occluder_shadow"]


@dataclasses.dataclass(frozen=True)
class OccluderLight:
    """The occluder's part of the light (docs/model.md §13): `visibility` V at the strand
    points (`[P]`, 0 where the occluder shadows them); per pixel (`[H, W]`, row 0 at the
    top) at the occluder's surface point: `omega` Ω (0 where it does not cover the pixel)
    and `surface_visibility` V (1 there)."""

    visibility: np.ndarray
    omega: np.ndarray
    surface_visibility: np.ndarray


def occluder_light(scene: Scene, geometry) -> OccluderLight | None:
    """The JAX renderer's `OccluderLight` (from its `Geometry`), to hand to `render_gl`
    with its Ω; None where the scene's occluder takes no part in the light."""
    if geometry.occluder_pixel is None or geometry.occluder_omega is None:
        return None
    cam = scene.camera
    pixel = np.asarray(geometry.occluder_pixel)
    omega = np.zeros(cam.width * cam.height)
    omega[pixel] = np.asarray(geometry.occluder_omega)
    surface = np.ones(cam.width * cam.height)
    surface[pixel] = np.asarray(geometry.occluder_visibility)
    return OccluderLight(
        np.asarray(geometry.light_visibility, np.float64),
        omega.reshape(cam.height, cam.width),
        surface.reshape(cam.height, cam.width),
    )


class OccluderSurface:
    """The occluder drawn into a view's raster (§9, §13): per pixel centre its surface
    point and normal (RGBA32F, w = 1 where covered) and the depth buffer."""

    def __init__(self, ctx, progs, occluder, view: View, depth_range: tuple[float, float]):
        import moderngl

        self.ctx = ctx
        w, h = view.width, view.height
        self.position = ctx.texture((w, h), 4, dtype="f4")
        self.normal = ctx.texture((w, h), 4, dtype="f4")
        self.depth = ctx.depth_texture((w, h))
        fbo = ctx.framebuffer(color_attachments=[self.position, self.normal], depth_attachment=self.depth)
        buffers = [fbo]
        try:
            fbo.use()
            ctx.viewport = (0, 0, w, h)
            fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
            ctx.disable(moderngl.BLEND)
            ctx.enable(moderngl.DEPTH_TEST)
            ctx.depth_func = "<"
            fbo.depth_mask = True
            uniforms = dict(
                raster_size=(float(w), float(h)), depth_range=depth_range, **view_uniforms("view", view)
            )
            if occluder.kind == "sphere":
                prog = progs["occluder_sphere"]
                set_uniforms(prog, center=vec(occluder.center), radius=float(occluder.radius), **uniforms)
                vao = ctx.vertex_array(prog, [])
                buffers.append(vao)
                vao.render(moderngl.TRIANGLES, vertices=3)
            else:
                prog = progs["occluder_mesh"]
                set_uniforms(prog, **uniforms)
                tri = occluder.triangles[drawable_triangles(view, occluder.vertices, occluder.triangles)]
                if tri.size:  # fires unless every triangle reaches the near plane
                    f4 = lambda a: ctx.buffer(np.ascontiguousarray(a, "f4").tobytes())  # noqa: E731
                    vbo = f4(occluder.vertices)
                    nbo = f4(vertex_normals(occluder.vertices, occluder.triangles))
                    ibo = ctx.buffer(np.ascontiguousarray(tri, "u4").tobytes())
                    vao = ctx.vertex_array(
                        prog,
                        [(vbo, "3f", "in_position"), (nbo, "3f", "in_normal")],
                        index_buffer=ibo,
                        index_element_size=4,
                    )
                    buffers += [vao, vbo, nbo, ibo]
                    vao.render(moderngl.TRIANGLES, vertices=tri.size)
            check(ctx, "occluder surface pass")
            raw = np.frombuffer(self.position.read(), dtype="f4").reshape(h, w, 4)
            self.covered = raw[..., 3] > 0  # GL's rows: row 0 at the bottom
            self.points = raw[self.covered][:, :3].astype(np.float64)
        finally:
            ctx.disable(moderngl.DEPTH_TEST)
            release(ctx, *buffers)

    def per_pixel(self, values: np.ndarray, fill: float) -> np.ndarray:
        """Values at `points` scattered to a `float32[H, W]` texture image (GL's rows)."""
        image = np.full(self.covered.shape, fill, "f4")
        image[self.covered] = values
        return image

    def release(self):
        release(self.ctx, self.position, self.normal, self.depth)


def occluder_shadow(
    ctx,
    progs,
    scene: Scene,
    strands: Strands,
    points: Points,
    surface: OccluderSurface,
    receiver_omega: np.ndarray,
) -> OccluderLight:
    """§13: the occluder drawn in its light view (`occluder_light_view`), then V at the
    strand points and at the occluder's surface points by the depth test."""
    r = scene.shadows.resolution
    view = occluder_light_view(scene.light, scene.strands.points, scene.occluder, r)
    _, z = view.project(np.concatenate([scene.strands.points, occluder_extent(scene.occluder)]))
    # The light's depth range with room on both sides: [0, 1) holds every surface point.
    lo, hi = float(z.min()), float(z.max())
    pad = 0.5 * (hi - lo) + 1e-6 * max(abs(lo), abs(hi), 1.0)
    light_surface = OccluderSurface(ctx, progs, scene.occluder, view, (lo - pad, hi + pad))
    out = ctx.buffer(reserve=4 * max(points.count, 1))
    comp = progs["occluder_visibility"]
    try:
        light_surface.position.use(0)
        points.buffer.bind_to_storage_buffer(0)
        out.bind_to_storage_buffer(1)
        set_uniforms(
            comp, light_position_map=0, count=points.count, resolution=r, **view_uniforms("light", view)
        )
        comp.run(group_x=workgroups(points.count))
        ctx.memory_barrier()
        check(ctx, "occluder shadow")
        v = np.frombuffer(out.read(), "f4")[: points.count].astype(np.float64)
    finally:
        release(ctx, out)
        light_surface.release()
    p = strands.count
    h, w = surface.covered.shape
    omega = surface.per_pixel(receiver_omega, 0.0)[::-1].astype(np.float64)
    vis = surface.per_pixel(v[p:], 1.0)[::-1].astype(np.float64)
    return OccluderLight(v[:p], omega.reshape(h, w), vis.reshape(h, w))


def draw_occluder_color(
    ctx, progs, scene: Scene, params, surface: OccluderSurface, occluder: OccluderLight | None, owned: list
) -> None:
    """§13: the occluder's colour k·ambient + τ·k·light·max(N·L, 0)·V where `surface` (the
    camera's) covers the pixel centre, into the bound framebuffer (blending and depth test
    off); Ω and V from `occluder`, Ω = 0 and V = 1 without it. The GL objects it creates
    go to `owned`, for the caller to release with its pass (also when this raises)."""
    import moderngl

    if scene.occluder is None:
        raise ValueError("draw_occluder_color: the scene has no occluder")
    w, h = scene.camera.width, scene.camera.height
    if occluder is None:
        omega_img = np.zeros((h, w), "f4")
        vis_img = np.ones((h, w), "f4")
    else:  # the per-pixel arrays have row 0 at the top, textures at the bottom
        omega_img = np.ascontiguousarray(occluder.omega[::-1], "f4")
        vis_img = np.ascontiguousarray(occluder.surface_visibility[::-1], "f4")
    omega_tex = ctx.texture((w, h), 1, omega_img.tobytes(), dtype="f4")
    vis_tex = ctx.texture((w, h), 1, vis_img.tobytes(), dtype="f4")
    owned += [omega_tex, vis_tex]
    prog = progs["occluder_color"]
    for unit, tex in enumerate((surface.position, surface.normal, omega_tex, vis_tex)):
        tex.use(unit)
    set_uniforms(
        prog,
        position_map=0,
        normal_map=1,
        omega_map=2,
        visibility_map=3,
        albedo=vec(scene.occluder.color),
        ambient=vec(params.ambient),
        kappa=float(params.kappa),
        **light_uniforms(scene),
    )
    occ_vao = ctx.vertex_array(prog, [])
    owned.append(occ_vao)
    occ_vao.render(moderngl.TRIANGLES, vertices=3)
    check(ctx, "occluder colour pass")
