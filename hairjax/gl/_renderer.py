"""The GL renderer: docs/model.md on OpenGL through moderngl; `render_gl` runs the passes.

Same inputs as the JAX renderer and the same NumPy code for what is not per-pixel maths:
the camera's draw order (`visibility_order`), the light's frame (`light_frame`), each
point's plane (`point_planes`) and the tangents. Everything per pixel or per texel runs in
shaders, one module per pass: the occluder's surface and shadow (`_occluder`, §13), Ω by
opacity maps (`_opacity_maps`, kim-2003 Routine 2: additive slices, four maps a pass in
the colour channels, Ω per pass of points) or exactly from per-texel fragment lists
(`_exact_opacity`), and the camera pass (`_camera_pass`: ribbons and coverage, shading at
points, the far-to-near "over" blending); `_shading` holds what depends on the shading model, `_buffers` the
strands on the GPU, `_patches` the hair-patch passes (§18).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .._geometry._projection import camera_view
from .._geometry._shadows import light_frame, with_receivers
from .._geometry_stage._setup import visibility_order
from .._laps import Laps
from .._patches import scene_patches, scene_point_colors
from .._scene._scene import Scene
from . import _deep_maps, _exact_opacity, _opacity_maps  # noqa: F401 (they register their passes)
from ._buffers import Points, Strands, resident_strands
from ._camera_pass import camera_depth_far, camera_pass
from ._context import get_context
from ._occluder import OccluderLight, OccluderSurface, occluder_shadow
from ._patches import patch_head, render_patches_gl
from ._programs import programs
from ._ribbons import check_expansion
from ._shadow_passes import PassDrawing, gl_shadow_pass

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


def render_gl(
    scene: Scene,
    params=None,
    *,
    clip_slices: bool = True,
    omega: np.ndarray | None = None,
    order: np.ndarray | None = None,
    occluder: OccluderLight | None = None,
    ribbons: str = "geometry-shader",
) -> GLResult:
    """Render `scene` with OpenGL.

    **Arguments:** `params` (default `scene.params`); `clip_slices`: draw into each
    opacity map only the segments whose depth range meets its slice (kim-2003 §4.2); off
    draws all of them into every map (the basic algorithm) — the same image, for timing;
    `omega`: use this Ω per point (`[P]`) instead of computing the shadows; `order`: draw
    the camera pass in this segment order instead of sorting (`visibility_order`, e.g. an
    order reused from an earlier view); `occluder`: with `omega`, the occluder's part of
    the light to use (`occluder_light(scene, geometry)` gives the JAX renderer's); required
    with `omega` when the scene has an occluder and shadows; `ribbons`: how the passes
    expand segments into quads, "geometry-shader" or "vertex-pulling" (`_ribbons`: the
    same images, bit for bit).
    """
    params = scene.params if params is None else params
    check_expansion(ribbons)
    if scene.patches is not None:
        return _render_patches(scene, params, omega, order, occluder)
    ctx = get_context()
    progs = programs(ctx)
    lap = Laps(wait=ctx.finish)  # seconds by pass, each waiting for GL's queued work
    view, _, depth, _, order = visibility_order(scene, order)
    depth_far = camera_depth_far(scene, view, depth)
    lighting = scene.occluder is not None and scene.shadows.casts
    strands = resident_strands(ctx, scene)
    surface = None
    try:
        lap("upload")
        if scene.occluder is not None:
            surface = OccluderSurface(ctx, progs, scene.occluder, view, (0.0, depth_far))
            lap("occluder surface")
        if omega is not None:
            omega = _given_omega(strands, omega)
            if lighting and occluder is None:
                raise ValueError(
                    "render_gl: with omega and a scene whose occluder takes part in "
                    "the light, pass occluder= too (occluder_light(scene, geometry))"
                )
        elif scene.shadows.casts:
            omega, made = _shadows(
                ctx, progs, scene, strands, surface, PassDrawing(clip_slices, ribbons), lap
            )
            if made is not None:  # the scene has an occluder: it takes part in the light
                occluder = made
        else:
            strands.write_omega(None)
        # Lighting: the occluder's part of the light, given with omega or made above.
        lit = lighting and occluder is not None
        strands.write_visibility(np.asarray(occluder.visibility, "f4") if lit and occluder else None)
        lit_by = occluder if lighting else None
        image = camera_pass(
            ctx, progs, scene, params, strands, view, order, depth_far, surface, lit_by, ribbons
        )
        lap("camera pass")
        return GLResult(image, omega, lap.timings, lit_by)
    finally:
        if surface is not None:
            surface.release()


def _given_omega(strands: Strands, omega) -> np.ndarray:
    """`omega` as `float32[P]`, uploaded for the camera pass."""
    omega = np.asarray(omega, dtype="f4").reshape(strands.count)
    strands.write_omega(omega)
    return omega


def _shadows(
    ctx,
    progs,
    scene: Scene,
    strands: Strands,
    surface: OccluderSurface | None,
    drawing: PassDrawing,
    lap: Laps,
) -> tuple[np.ndarray, OccluderLight | None]:
    """(Ω per strand point, uploaded for the camera pass; the occluder's part of the light,
    None without an occluder): the scene's shadow method's passes from the light, over the
    strands' points and the occluder surface's points (§7, §13), drawn as `drawing` says."""
    frame = light_frame(
        scene.strands.points,
        strands.segments,
        scene.strands.width,
        scene.light,
        scene.shadows.resolution,
        scene.strands.width_units,
    )
    points = Points(ctx, strands, None if surface is None else surface.points)
    try:
        frame = with_receivers(frame, points.receivers)
        omega_all = gl_shadow_pass(scene.shadows.method)(ctx, progs, scene, strands, frame, points, drawing)
        omega = omega_all[: strands.count].copy()
        strands.write_omega(omega)
        lap("shadows")
        if surface is None:
            return omega, None
        occluder = occluder_shadow(ctx, progs, scene, strands, points, surface, omega_all[strands.count :])
        lap("occluder shadow")
        return omega, occluder
    finally:
        points.release()


def _render_patches(scene: Scene, params, omega, order, occluder) -> GLResult:
    """docs/model.md §18: slide 17's four passes in GL over the patch mesh, after the
    scene's occluder (the head, slide 16). The per-point colours and the occluder's part
    of the light (Ω and V at its surface) come from the JAX geometry and shading: GL here
    checks visibility and compositing, not the shading (the ribbon path checks that)."""
    if omega is not None or order is not None or occluder is not None:
        raise ValueError("a hair-patch scene takes none of `omega`, `order`, `occluder`")
    lap = Laps()
    colors = np.asarray(scene_point_colors(scene, params), np.float64)
    head = patch_head(scene, params)
    lap("point colours (JAX)")
    image = render_patches_gl(
        get_context(), camera_view(scene.camera), scene_patches(scene), colors, scene.background, head
    )
    lap("four passes")  # its image read back: GL has finished
    return GLResult(image, None, lap.timings)
