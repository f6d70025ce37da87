"""Hair patches in GL: scheuermann-2004 slide 17's four passes (docs/model.md §18).

1. prime Z: alpha test passes opaque fragments only, no culling, Z writes on, Z test
   LESS, colour writes off;
2. opaque: no culling, Z writes off, Z test EQUAL (only the front-most opaque fragment);
3. transparent back faces: alpha test passes non-opaque fragments, front faces culled,
   Z writes off, Z test LESS, blending "over";
4. transparent front faces: back faces culled, Z writes on, Z test LESS, "over".

Triangles are drawn in the order of `Patches.triangles` (slide 14's static order) in every
pass; GL keeps primitive order for depth test and blending within a draw call. A scene's
occluder is the head, drawn before the passes (slide 16: "draw head first"): its surface
pass (§13) writes its depths, then its colour fills the pixels it covers.
"""

from __future__ import annotations

import dataclasses
from typing import Any, NamedTuple

import numpy as np

from .._geometry._occluder import drawable_triangles
from .._geometry._projection import View
from .._geometry_stage._stage import geometry_stage
from .._patches import Patches
from .._scene._scene import Scene
from ._camera_pass import blend_over, camera_depth_far
from ._context import check, release
from ._occluder import OccluderLight, OccluderSurface, draw_occluder_color, occluder_light
from ._programs import programs
from ._uniforms import set_uniforms, view_uniforms

__all__ = ["PatchHead", "patch_head", "render_patches_gl"]


@dataclasses.dataclass(frozen=True)
class PatchHead:
    """The head under the patches: `scene`'s occluder, lit with `params` (ambient, κ) and
    `light`, its part of the light (Ω and V per pixel, §13; None: Ω = 0, V = 1)."""

    scene: Scene
    params: Any
    light: OccluderLight | None


def patch_head(scene: Scene, params) -> PatchHead | None:
    """`scene`'s occluder as the head (None without one), with the JAX geometry's part of
    the light (`occluder_light`: Ω and V at its surface points, §13), as the patches'
    point colours are the JAX shading's."""
    if scene.occluder is None:
        return None
    return PatchHead(scene, params, occluder_light(scene, geometry_stage(scene)))


def render_patches_gl(
    ctx, view: View, patches: Patches, point_colors: np.ndarray, background, head: PatchHead | None = None
) -> np.ndarray:
    """The patches drawn at `view` with the per-point colours `point_colors` `[P, 3]`
    (each vertex carries its strand point's colour) over `background` (RGB, alpha 0), and
    over `head` where it covers the pixel (drawn first, alpha 1).
    Returns `float32[H, W, 4]` linear RGBA, row 0 at the top."""
    import moderngl

    w, h = view.width, view.height
    progs = programs(ctx)
    tri = patches.triangles[drawable_triangles(view, patches.vertices, patches.triangles)]
    _, depth = view.project(patches.vertices)
    far = _depth_far(view, depth[tri], head)
    color = ctx.texture((w, h), 4, dtype="f4")
    surface = None if head is None else OccluderSurface(ctx, progs, head.scene.occluder, view, (0.0, far))
    depth_tex = ctx.depth_texture((w, h)) if surface is None else surface.depth
    fbo = ctx.framebuffer(color_attachments=[color], depth_attachment=depth_tex)
    objects = [fbo, color, depth_tex if surface is None else None]
    try:
        fbo.use()
        ctx.viewport = (0, 0, w, h)
        bg = [float(x) for x in np.asarray(background, np.float64).ravel()]
        fbo.depth_mask = surface is None  # keep the head's depths
        fbo.clear(bg[0], bg[1], bg[2], 0.0, depth=1.0)
        if head is not None and surface is not None:  # slide 16: the head first, its colour at alpha 1
            ctx.disable(moderngl.BLEND | moderngl.DEPTH_TEST)
            draw_occluder_color(ctx, progs, head.scene, head.params, surface, head.light, objects)
        if tri.size:  # fires unless every triangle reaches the near plane
            vao = _patch_vertex_array(ctx, progs["patch"], patches, point_colors, tri, objects)
            set_uniforms(
                progs["patch"],
                raster_size=(float(w), float(h)),
                depth_range=(0.0, far),
                core=float(patches.core),
                strands=int(patches.strands),
                strand_alpha=float(patches.strand_alpha),
                tips=float(patches.tips),
                **view_uniforms("view", view),
            )
            _four_passes(ctx, fbo, progs["patch"], vao, tri.size)
        image = np.frombuffer(color.read(), dtype="f4").reshape(h, w, 4)[::-1].copy()
    finally:
        ctx.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE | moderngl.BLEND)
        fbo.depth_mask = True
        fbo.color_mask = (True,) * 4
        ctx.depth_func = "<"
        release(ctx, *objects)
        if surface is not None:
            surface.release()
    return image


def _depth_far(view: View, drawn_depths: np.ndarray, head: PatchHead | None) -> float:
    """The far end of the depth buffer's range for the drawn triangles' depths (and the
    head's): drawn depths lie in (0, max], and far = 2·max keeps them inside [0, 1)."""
    if head is None:
        near = view.near if np.isfinite(view.near) else 1.0
        return 2.0 * float(max(np.max(drawn_depths, initial=0.0), near))
    return camera_depth_far(head.scene, view, drawn_depths.ravel())


def _patch_vertex_array(
    ctx, prog, patches: Patches, point_colors: np.ndarray, tri: np.ndarray, objects: list
):
    """The patch mesh's vertices (position, u, v along the patch, patch, its strand point's
    colour) and the drawn triangles' indices on the GPU; its objects appended to `objects`."""
    f4 = lambda a: ctx.buffer(np.ascontiguousarray(a, "f4").tobytes())  # noqa: E731
    vbo, ubo, vvbo = f4(patches.vertices), f4(patches.u), f4(patches.along())
    pbo = ctx.buffer(np.ascontiguousarray(patches.patch_of(), "u4").tobytes())
    cbo = f4(np.asarray(point_colors, np.float64)[patches.point])
    ibo = ctx.buffer(np.ascontiguousarray(tri, "u4").tobytes())
    vao = ctx.vertex_array(
        prog,
        [
            (vbo, "3f", "in_position"),
            (ubo, "1f", "in_u"),
            (vvbo, "1f", "in_v"),
            (pbo, "1u", "in_patch"),
            (cbo, "3f", "in_color"),
        ],
        index_buffer=ibo,
        index_element_size=4,
    )
    objects += [vao, vbo, ubo, vvbo, pbo, cbo, ibo]
    return vao


class _Pass(NamedTuple):
    """One of slide 17's passes: which fragments the alpha test keeps (the opaque ones or
    the others), the faces culled, whether Z is written, the Z test, whether colour is
    written, and whether it blends "over"."""

    opaque: bool
    cull: str | None
    z_write: bool
    z_test: str
    colour: bool
    blend: bool


_PASSES = (
    _Pass(True, None, True, "<", False, False),  # 1. prime Z
    _Pass(True, None, False, "==", True, False),  # 2. opaque parts
    _Pass(False, "front", False, "<", True, True),  # 3. transparent back faces
    _Pass(False, "back", True, "<", True, True),  # 4. transparent front faces
)


def _four_passes(ctx, fbo, prog, vao, vertices: int) -> None:
    """Slide 17's four passes over the drawn triangles, in their order (module docstring)."""
    import moderngl

    ctx.enable(moderngl.DEPTH_TEST)
    ctx.front_face = "ccw"
    for p in _PASSES:
        set_uniforms(prog, opaque_pass=p.opaque)
        if p.cull is None:
            ctx.disable(moderngl.CULL_FACE)
        else:
            ctx.enable(moderngl.CULL_FACE)
            ctx.cull_face = p.cull
        fbo.depth_mask = p.z_write
        ctx.depth_func = p.z_test
        fbo.color_mask = (p.colour,) * 4
        if p.blend:
            blend_over(ctx)
        else:
            ctx.disable(moderngl.BLEND)
        vao.render(moderngl.TRIANGLES, vertices=vertices)
        check(ctx, "hair patch pass")
