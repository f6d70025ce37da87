"""Shader programs, compiled once per context from `shaders/` and the shared constants.

The constants include is generated from `hairjax/_constants.py`, so GLSL and JAX read one
definition; `model.glsl` holds the model's formulas (docs/model.md) for every shader.
"""

from __future__ import annotations

from importlib import resources

from .. import _constants
from .._shading import shading_model_class, shading_model_names
from ._context import GLError

__all__ = ["COMPUTE_GROUP", "programs", "constants_glsl", "shader_source", "workgroups"]

COMPUTE_GROUP = 64  # local_size_x of every compute shader (shaders/*.comp)


def workgroups(count: int) -> int:
    """How many work groups of `COMPUTE_GROUP` invocations cover `count` items."""
    return (count + COMPUTE_GROUP - 1) // COMPUTE_GROUP


def constants_glsl() -> str:
    """GLSL `const` declarations for every constant in hairjax/_constants.py."""
    lines = ["// Generated from hairjax/_constants.py: do not edit."]
    for name in dir(_constants):
        value = getattr(_constants, name)
        if not name.isupper() or isinstance(value, bool):
            continue
        if isinstance(value, int):
            lines.append(f"const int {name} = {value};")
        elif isinstance(value, float):
            lines.append(f"const float {name} = {value!r};")
        elif isinstance(value, tuple) and all(isinstance(x, float) for x in value):
            items = ", ".join(repr(x) for x in value)
            kind = "vec3" if len(value) == 3 else f"float[{len(value)}]"
            lines.append(f"const {kind} {name} = {kind}({items});")
    # Each registered model's branch of the camera shader (`AbstractShadingModel.gl_id`).
    for name in shading_model_names():
        gl_id = shading_model_class(name).gl_id
        if gl_id is not None:
            lines.append(f"const int SHADING_{name.upper().replace('-', '_')} = {gl_id};")
    return "\n".join(lines) + "\n"


def shader_source(name: str) -> str:
    return resources.files(__package__).joinpath("shaders", name).read_text()


# The ribbon passes' fragment shaders: each is one program per way of drawing ribbons
# (`_ribbons`): "<name>" with the geometry shader, "<name> pulled" by vertex pulling, whose
# points are placed and shaded by "<name> points" (strand.vert alone, its outputs captured):
# a program per pass, as each keeps its uniforms (a light pass's `given_screen`).
_RIBBON_FRAGMENTS = {
    "camera": "camera.frag",
    "light_slice": "light_slice.frag",
    "light_list": "light_list.frag",
    "deep_first": "deep_first.frag",
    "deep_layers": "deep_layers.frag",
}
_RIBBON_PROGRAMS = {
    program: stages
    for name, fragment in _RIBBON_FRAGMENTS.items()
    for program, stages in (
        (name, dict(vertex_shader="strand.vert", geometry_shader="ribbon.geom", fragment_shader=fragment)),
        (f"{name} pulled", dict(vertex_shader="ribbon_pulled.vert", fragment_shader=fragment)),
        (f"{name} points", dict(vertex_shader="strand.vert")),
    )
}
# What "<name> points" captures per point, for the pulled ribbons (`_ribbons.POINT_FLOATS`).
_POINT_OUTPUTS = ("VertexOut.screen", "VertexOut.color", "VertexOut.alpha", "VertexOut.width")
_PROGRAMS = {
    **_RIBBON_PROGRAMS,
    "light_seed": dict(vertex_shader="fullscreen.vert", fragment_shader="light_seed.frag"),
    "occluder_sphere": dict(vertex_shader="fullscreen.vert", fragment_shader="occluder_sphere.frag"),
    "occluder_mesh": dict(vertex_shader="occluder_mesh.vert", fragment_shader="occluder_mesh.frag"),
    "occluder_color": dict(vertex_shader="fullscreen.vert", fragment_shader="occluder_color.frag"),
    "patch": dict(vertex_shader="patch.vert", fragment_shader="patch.frag"),
}
_COMPUTE = {
    "omega_maps": "omega_maps.comp",
    "omega_exact": "omega_exact.comp",
    "omega_deep": "omega_deep.comp",
    "occluder_visibility": "occluder_visibility.comp",
}
_CACHE: dict = {}


def programs(ctx) -> dict:
    """All programs for `ctx`, by name (compiled on first use)."""
    key = id(ctx)
    if key not in _CACHE:
        # moderngl expands includes one level deep: put the constants into the model.
        ctx.includes["hairjax_model"] = shader_source("model.glsl").replace(
            '#include "hairjax_constants"', constants_glsl()
        )
        ctx.includes["hairjax_ribbon_fragment"] = shader_source("ribbon_fragment.glsl")
        ctx.includes["hairjax_ribbon_quad"] = shader_source("ribbon_quad.glsl")
        built = {}
        for name, stages in _PROGRAMS.items():
            captured = dict(varyings=_POINT_OUTPUTS) if name.endswith(" points") else {}
            try:
                built[name] = ctx.program(**{k: shader_source(v) for k, v in stages.items()}, **captured)
            except Exception as err:
                raise GLError(
                    f"shader program {name!r} ({', '.join(stages.values())}) failed to build:\n{err}"
                ) from err
        for name, file in _COMPUTE.items():
            try:
                built[name] = ctx.compute_shader(shader_source(file))
            except Exception as err:
                raise GLError(f"compute shader {name!r} ({file}) failed to build:\n{err}") from err
        _CACHE[key] = built
    return _CACHE[key]


def clear_cache() -> None:
    """Forget compiled programs (tests that change shader sources call this)."""
    _CACHE.clear()
