"""The camera pass (docs/model.md §5, §6; kim-2003 §3's drawing pass): the occluder's
colour, then the hair far to near as shaded ribbons "over" the background, with the depth
test against the occluder."""

from __future__ import annotations

import numpy as np

from .._geometry._occluder import drawable_triangles
from .._geometry._projection import View
from .._scene._scene import Scene
from ._buffers import Strands
from ._context import check, release
from ._occluder import OccluderLight, OccluderSurface, draw_occluder_color
from ._ribbons import Ribbons
from ._shading import lookup_texture, shading_uniforms, streak_texture, use_shading_textures
from ._uniforms import light_uniforms, vec, view_uniforms

__all__ = ["blend_over", "camera_depth_far", "camera_pass"]


def blend_over(ctx) -> None:
    """Blend "over" (docs/model.md §6): C ← a c + (1 − a) C for colour, and
    A ← a + (1 − a) A, i.e. 1 − Π(1 − α), for alpha."""
    import moderngl

    ctx.enable(moderngl.BLEND)
    ctx.blend_func = (
        moderngl.SRC_ALPHA,
        moderngl.ONE_MINUS_SRC_ALPHA,
        moderngl.ONE,
        moderngl.ONE_MINUS_SRC_ALPHA,
    )


def camera_depth_far(scene: Scene, view: View, depth: np.ndarray) -> float:
    """The camera depth mapped to 1 in the depth buffer: anything drawn lies in (near, far)."""
    cam = scene.camera
    # No floor at 1 unit: depth/far is stored in 2⁻²⁴ steps, so a floor above a tiny scene's
    # depths would spend its digits on empty range.
    far = 2.0 * float(max(np.max(depth, initial=0.0), cam.near))
    occ = scene.occluder
    if occ is not None and occ.kind == "sphere":
        c = np.asarray(occ.center) - view.origin
        far = max(far, 2.0 * (float(c @ view.forward) + occ.radius))
    elif occ is not None and occ.vertices is not None and occ.triangles is not None:  # a mesh
        vertices, triangles = np.asarray(occ.vertices), np.asarray(occ.triangles)  # arrays already
        drawn = triangles[drawable_triangles(view, vertices, triangles)]
        if drawn.size:  # fires unless every triangle reaches the near plane
            far = max(far, 2.0 * float(np.max((vertices[drawn] - view.origin) @ view.forward)))
    return far


def camera_pass(
    ctx,
    progs,
    scene: Scene,
    params,
    strands: Strands,
    view: View,
    order: np.ndarray,
    depth_far: float,
    surface: OccluderSurface | None,
    occluder: OccluderLight | None,
    expansion: str,
) -> np.ndarray:
    """The image (`float32[H, W, 4]`, row 0 at the top): the occluder's colour where
    `surface` covers the pixel (§13, lit by `occluder`), then the segments `order` far to near
    as ribbons shaded at their points (§5, §6, §8), depths in (near, `depth_far`), expanded
    as `expansion` says (`_ribbons`)."""
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
    extra: list = []
    table = lookup_texture(ctx, scene, params)
    streak = streak_texture(ctx, scene)
    try:
        fbo.use()
        ctx.viewport = (0, 0, w, h)
        bg = vec(scene.background)
        fbo.depth_mask = surface is None  # keep the occluder's depths
        fbo.clear(*bg, 0.0, depth=1.0)
        common = dict(
            raster_size=(float(w), float(h)),
            depth_far=depth_far,
            world_width=scene.strands.width_units == "world",
            **view_uniforms("view", view),
            **light_uniforms(scene),
        )
        if surface is not None:
            # §13: the occluder's colour where its surface pass covered the pixel centre.
            ctx.disable(moderngl.BLEND | moderngl.DEPTH_TEST)
            fbo.depth_mask = False
            draw_occluder_color(ctx, progs, scene, params, surface, occluder, extra)
            ctx.enable(moderngl.DEPTH_TEST)
            ctx.depth_func = "<"
        else:
            ctx.disable(moderngl.DEPTH_TEST)
        # kim-2003 §3: hair far to near, depth test on (if anything wrote depth), no depth
        # writes; "over" for colour, and 1 − Π(1 − α) for alpha.
        fbo.depth_mask = False
        blend_over(ctx)
        ctx.blend_equation = moderngl.FUNC_ADD
        ribbons = Ribbons(ctx, progs, "camera", strands, ibo, len(order), expansion)
        extra.append(ribbons)
        ribbons.set_uniforms(shade=True, eye=vec(view.origin), **shading_uniforms(scene, params), **common)
        use_shading_textures(ribbons.point_program, scene, table, streak)
        ribbons.draw()
        check(ctx, "camera pass")
        data = np.frombuffer(color.read(), dtype="f4").reshape(h, w, 4)
        return data[::-1].copy()  # GL's row 0 is the bottom
    finally:
        ctx.disable(moderngl.BLEND | moderngl.DEPTH_TEST)
        release(ctx, ibo, fbo, color, *([own_depth] if own_depth is not None else []), *extra, table, streak)
