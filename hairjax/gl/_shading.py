"""Everything on the GL side that depends on the shading model: Kajiya-Kay (docs/model.md
§8, kim-2003 §5), its lookup table (§14, wenzel-2002), Scheuermann (§17, scheuermann-2004)
and the streaks (§16, wenzel-2002). The per-point inputs, the camera pass's `shading` and
`scheuermann` uniforms and the textures it samples; the shaders' side is model.glsl.
"""

from __future__ import annotations

import numpy as np

from .._lookup import LOOKUP_MODELS, kajiya_kay_table
from .._scene import Scene
from .._scheuermann import ScheuermannParams, scheuermann_inputs
from .._shading import ShadingParams
from .._streaks import strand_coordinates, streak_prefix
from .._streaks import streak_texture as streak_values
from ._programs import SHADING_MODEL_IDS
from ._uniforms import set_uniforms, vec

__all__ = ["lookup_texture", "point_inputs", "shading_uniforms", "streak_texture", "use_shading_textures"]


def point_inputs(scene: Scene, tangent: np.ndarray, color: np.ndarray, alpha: np.ndarray,
                 segments: np.ndarray) -> tuple[np.ndarray, np.ndarray, list]:
    """The strands' per-point `color` and `alpha` as the shading model changes them, and its
    further vertex attributes as `(values, format, name)`: §17's normal and (shift, mask)
    maps (scheuermann-2004), §16's hair coordinate u_i; none for Kajiya-Kay."""
    s = scene.strands
    attributes = []
    if scene.shading_model == "scheuermann":
        pts, factor, segment_alpha = scheuermann_inputs(s, tangent, scene.scheuermann_maps)
        color = color * factor
        if segment_alpha is not None:
            # ribbon.geom takes a segment's alpha from its first point.
            alpha = alpha.copy()
            alpha[segments[:, 0]] *= segment_alpha
        attributes = [(pts.normal, "3f", "in_normal"),
                      (np.stack([pts.shift, pts.mask], axis=1), "2f", "in_maps")]
    if scene.streaks is not None:  # §16: each point's hair coordinate u_i
        u = strand_coordinates(scene.streaks, s.num_strands)[s.strand_of_point]
        attributes.append((u, "f", "in_streak"))
    return color, alpha, attributes


def shading_uniforms(scene: Scene, params) -> dict:
    """The `shading` (and for §17 the `scheuermann`) uniforms of the camera pass."""
    uniforms = {"shading.model": SHADING_MODEL_IDS[scene.shading_model],
                "shading.kappa": float(params.kappa)}
    if scene.shading_model == "scheuermann":
        if not isinstance(params, ScheuermannParams):
            raise TypeError("shading model 'scheuermann' takes ScheuermannParams, "
                            f"got {type(params).__name__}")
        for name in ("kd", "ambient", "primary_color", "secondary_color"):
            uniforms[f"scheuermann.{name}"] = vec(getattr(params, name))
        for name in ("primary_exponent", "secondary_exponent", "primary_shift", "secondary_shift"):
            uniforms[f"scheuermann.{name}"] = float(getattr(params, name))
        return uniforms
    return {**uniforms, "shading.kd": vec(params.kd), "shading.ks": vec(params.ks),
            "shading.ambient": vec(params.ambient), "shading.shininess": float(params.shininess)}


def lookup_texture(ctx, scene: Scene, params: ShadingParams):
    """§14: the lookup model's table (built by the JAX code, `kajiya_kay_table`) as an
    RG32F texture sampled with LINEAR filtering and CLAMP_TO_EDGE; None for other models."""
    import moderngl

    if scene.shading_model not in LOOKUP_MODELS:
        return None
    table = kajiya_kay_table(params.shininess, scene.lookup_size, LOOKUP_MODELS[scene.shading_model])
    n = scene.lookup_size
    tex = ctx.texture((n, n), 2, np.ascontiguousarray(table, dtype="f4").tobytes(), dtype="f4")
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
        set_uniforms(prog, kajiya_kay_table=0)
    set_uniforms(prog, streaks=streak is not None)
    if streak is not None:
        streak.use(1)
        set_uniforms(prog, streak_texture=1, streak_texels=scene.streaks.texels,
                     streak_width=float(scene.streaks.width))
