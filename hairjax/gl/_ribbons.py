"""How a GL pass draws the strands' segments as ribbons (docs/model.md §5, §11).

Each segment is one quad around it (`ribbon_corner`, shaders/ribbon_quad.glsl), and the
pass's fragment shader decides coverage. Two ways make the quads, a render's choice
(`render_gl(..., ribbons=...)`), an explicit value rather than a setting:

- `"geometry-shader"` (the default): strand.vert per segment end over GL_LINES,
  ribbon.geom emitting the quad. On llvmpipe, the one driver measured, it is the faster
  (BENCHMARKS.md, "Ribbons without a geometry shader").
- `"vertex-pulling"`: strand.vert places and shades every point once, its outputs
  captured by transform feedback; then six vertices per segment (ribbon_pulled.vert, no
  geometry shader) read their segment's ends from storage buffers, as TressFX draws
  hair. GPUs run geometry shaders' amplification slowly: the choice for a GPU to
  measure (experiments/18).

Both make the same fragments with the same values, so the same images and Ω, bit for bit
(tests/gl/test_ribbons.py).
"""

from __future__ import annotations

from typing import Any

from ._buffers import Strands
from ._context import release
from ._uniforms import set_uniforms

__all__ = ["RIBBON_EXPANSIONS", "Ribbons", "check_expansion"]

RIBBON_EXPANSIONS = ("geometry-shader", "vertex-pulling")

# Floats strand.vert's transform feedback captures per point: screen.xyz, color.rgb,
# alpha, width (ribbon_pulled.vert's POINT_FLOATS).
POINT_FLOATS = 8
# The storage-buffer bindings ribbon_pulled.vert reads: the passes' own take 0 … 5.
SHADED_BINDING, ENDS_BINDING = 6, 7


def check_expansion(expansion: str) -> str:
    """`expansion`, one of RIBBON_EXPANSIONS; `ValueError` otherwise."""
    if expansion not in RIBBON_EXPANSIONS:
        raise ValueError(f"ribbons must be one of {', '.join(RIBBON_EXPANSIONS)}; got {expansion!r}")
    return expansion


class Ribbons:
    """One pass's ribbons: the segments of `index_buffer` (`Strands.index_buffer`, of
    `segments` segments) drawn with program `name`'s fragment shader (hairjax/gl/_programs.py),
    expanded as `expansion` says; `screen` (`Strands.screen_buffer`) for a light pass.
    Uniforms go to every program of the pass (`set_uniforms`); strand.vert's, which place
    and shade the points, are read at the first `draw`."""

    def __init__(
        self,
        ctx,
        progs,
        name: str,
        strands: Strands,
        index_buffer,
        segments: int,
        expansion: str,
        screen=None,
    ):
        self.ctx, self.segments, self.points = ctx, segments, strands.count
        self.expansion = check_expansion(expansion)
        self.index_buffer = index_buffer
        self.shaded: Any = None  # vertex pulling: the points' captured outputs, from the first draw
        if self.expansion == "geometry-shader":
            self.point_program = self.program = progs[name]
            self.point_vao = None
            self.vao = strands.vertex_array(self.program, index_buffer, screen)
        else:
            self.point_program, self.program = progs[f"{name} points"], progs[f"{name} pulled"]
            self.point_vao = strands.vertex_array(self.point_program, None, screen)
            self.vao = ctx.vertex_array(self.program, [])

    def set_uniforms(self, **values) -> None:
        """Set uniforms of the pass's programs; each takes the names it has."""
        set_uniforms(self.point_program, **values)
        if self.program is not self.point_program:
            set_uniforms(self.program, **values)

    def draw(self, first: int = 0, count: int | None = None) -> None:
        """Draw segments `first` … `first + count − 1` of the index buffer (all by default)."""
        import moderngl

        count = self.segments - first if count is None else count
        if count <= 0:
            return
        if self.point_vao is None:
            self.vao.render(moderngl.LINES, vertices=2 * count, first=2 * first)
            return
        if self.shaded is None:
            self.shaded = self.ctx.buffer(reserve=4 * POINT_FLOATS * max(self.points, 1))
            self.point_vao.transform(self.shaded, mode=moderngl.POINTS, vertices=self.points)
        self.shaded.bind_to_storage_buffer(SHADED_BINDING)
        self.index_buffer.bind_to_storage_buffer(ENDS_BINDING)
        set_uniforms(self.program, first_segment=first)
        self.vao.render(moderngl.TRIANGLES, vertices=6 * count)

    def release(self) -> None:
        release(self.ctx, *(x for x in (self.vao, self.point_vao, self.shaded) if x is not None))
