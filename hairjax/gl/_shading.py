"""The GL side of the shading stage: what the camera pass takes from the scene's shading
model object (its `gl_id`, `gl_uniforms`, `gl_table`, `gl_attributes` and per-point
inputs, hairjax/_shading/) and from the streaks (§16, wenzel-2002). The shaders' side of
each model is its branch in strand.vert and model.glsl.
"""

from __future__ import annotations

import numpy as np

from .._errors import SceneError
from .._scene._scene import Scene
from .._shading._streaks import strand_coordinates, streak_prefix
from .._shading._streaks import streak_texture as streak_values
from ._uniforms import set_uniforms

__all__ = ["lookup_texture", "point_inputs", "shading_uniforms", "streak_texture", "use_shading_textures"]


def point_inputs(
    scene: Scene, tangent: np.ndarray, color: np.ndarray, alpha: np.ndarray, segments: np.ndarray
) -> tuple[np.ndarray, np.ndarray, list]:
    """The strands' per-point `color` and `alpha` as the shading model changes them
    (`point_inputs`: §17's textures), and its further vertex attributes as
    `(values, format, name)` (`gl_attributes`: §17's normal and (shift, mask) maps), with
    §16's hair coordinate u_i; none for Kajiya-Kay."""
    s = scene.strands
    inputs = scene.shading.point_inputs(s, tangent)
    if inputs.color_factor is not None:
        color = color * inputs.color_factor
    if inputs.segment_alpha is not None:
        # ribbon.geom takes a segment's alpha from its first point.
        alpha = alpha.copy()
        alpha[segments[:, 0]] *= inputs.segment_alpha
    attributes = list(scene.shading.gl_attributes(inputs))
    if scene.streaks is not None:  # §16: each point's hair coordinate u_i
        u = strand_coordinates(scene.streaks, s.num_strands)[s.strand_of_point]
        attributes.append((u, "f", "in_streak"))
    return color, alpha, attributes


def shading_uniforms(scene: Scene, params) -> dict:
    """The `shading` uniforms of the camera pass: the model's branch (`gl_id`) and κ, and
    the model's own (`gl_uniforms`)."""
    model = scene.shading
    if model.gl_id is None:
        raise TypeError(f"shading model {model.name!r} has no GL renderer (gl_id is None)")
    reason = model.gl_unsupported()
    if reason is not None:  # a configuration its branch does not draw
        raise SceneError(reason)
    if not isinstance(params, model.params_type):
        raise TypeError(
            f"shading model {model.name!r} takes {model.params_type.__name__}, got {type(params).__name__}"
        )
    return {"shading.model": model.gl_id, "shading.kappa": float(params.kappa), **model.gl_uniforms(params)}


def lookup_texture(ctx, scene: Scene, params):
    """The model's table (`gl_table`, built by the JAX code, `[rows, columns, c]`) as a
    float32 texture of c components, LINEAR filtering and CLAMP_TO_EDGE: §14's Kajiya-Kay
    table (sampled) or §19's dual-scattering tables (read with texelFetch); None for
    models without one."""
    import moderngl

    table = scene.shading.gl_table(params)
    if table is None:
        return None
    rows, columns, components = table.shape
    data = np.ascontiguousarray(table, dtype="f4").tobytes()
    tex = ctx.texture((columns, rows), components, data, dtype="f4")
    tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
    tex.repeat_x = tex.repeat_y = False  # CLAMP_TO_EDGE
    return tex


def streak_texture(ctx, scene: Scene):
    """§16: texel k = (N_{k mod m}, P_k), k = 0 … m, as an RG32F texture read with
    texelFetch (the mean over a hair's span is computed from it exactly); None without streaks."""
    if scene.streaks is None:
        return None
    texture = streak_values(scene.streaks)
    data = np.stack([np.append(texture, texture[0]), streak_prefix(texture)], axis=1)
    return ctx.texture((len(data), 1), 2, np.ascontiguousarray(data, dtype="f4").tobytes(), dtype="f4")


def use_shading_textures(prog, scene: Scene, table, streak) -> None:
    """Bind `lookup_texture`'s table (unit 0) and `streak_texture`'s texture (unit 1) to the
    camera program, with the streaks' uniforms; either may be None."""
    if table is not None:
        table.use(0)
        # The model's sampler (the other is not in its branch of strand.vert).
        set_uniforms(prog, kajiya_kay_table=0, marschner_tables=0)
    set_uniforms(prog, streaks=streak is not None)
    if streak is not None and scene.streaks is not None:  # the texture is made from scene.streaks
        streak.use(1)
        set_uniforms(
            prog,
            streak_texture=1,
            streak_texels=scene.streaks.texels,
            streak_width=float(scene.streaks.width),
        )
