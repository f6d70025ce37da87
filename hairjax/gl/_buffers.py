"""The hair on the GPU: the strand points' vertex buffers every ribbon pass draws from,
and the points whose Ω the shadow passes compute (docs/model.md §7, §13)."""

from __future__ import annotations

import numpy as np

from .._scene._scene import Scene
from .._values._strands import tangents
from ._shading import point_inputs

__all__ = ["Points", "Strands"]


class Strands:
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
        color, alpha, inputs = point_inputs(scene, tangent, color, alpha, self.segments)
        # The shading model's further per-point inputs (§16, §17), when it has any.
        self.extra = [(f4(values), fmt, name) for values, fmt, name in inputs]
        self.position = f4(s.points)
        self.tangent = f4(tangent)
        self.color = f4(color)
        self.alpha = f4(alpha)
        self.width = f4(s.width[per_point])
        self.omega = f4(np.zeros(s.num_points))
        self.visibility = f4(np.ones(s.num_points))

    def vertex_array(self, prog, index_buffer):
        return self.ctx.vertex_array(
            prog,
            [
                (self.position, "3f", "in_position"),
                (self.tangent, "3f", "in_tangent"),
                (self.color, "3f", "in_color"),
                (self.alpha, "f", "in_alpha"),
                (self.width, "f", "in_width"),
                (self.omega, "f", "in_omega"),
                (self.visibility, "f", "in_visibility"),
                *self.extra,
            ],
            index_buffer=index_buffer,
            index_element_size=4,
            skip_errors=True,
        )

    def index_buffer(self, segment_ids: np.ndarray):
        """Endpoints of the given segments, in order, for GL_LINES."""
        pairs = self.segments[segment_ids].astype("u4")
        return self.ctx.buffer(pairs.tobytes() if pairs.size else b"\0" * 8)  # no segments: GL needs ≥ 1 byte

    def release(self):
        for b in (
            self.position,
            self.tangent,
            self.color,
            self.alpha,
            self.width,
            self.omega,
            self.visibility,
            *(buffer for buffer, _, _ in self.extra),
        ):
            b.release()


class Points:
    """The points whose Ω the shadow passes compute: the strand points, then the
    occluder's surface points (`receivers`, §13) when there are any."""

    def __init__(self, ctx, strands: Strands, receivers):
        self.receivers = receivers if receivers is not None and len(receivers) else None
        self.count = strands.count + (0 if self.receivers is None else len(self.receivers))
        self.own = None
        self.buffer = strands.position
        if self.receivers is not None:
            s_pos = np.frombuffer(strands.position.read(), "f4").reshape(-1, 3)
            self.own = ctx.buffer(np.concatenate([s_pos, self.receivers.astype("f4")]).tobytes())
            self.buffer = self.own

    def release(self):
        if self.own is not None:
            self.own.release()
