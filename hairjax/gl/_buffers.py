"""The hair on the GPU: the strand points' vertex buffers every ribbon pass draws from,
and the points whose Ω the shadow passes compute (docs/model.md §7, §13).

The strands are uploaded once per scene and context (`resident_strands`): every later GL
render of the same scene object draws from the same buffers. They live in the per-scene
cache (`_cache`), so they go when the scene goes or is forgotten, and their buffers are
released with them."""

from __future__ import annotations

import weakref

import numpy as np

from .._cache import cached
from .._scene._scene import Scene
from .._values._strands import tangents
from ._shading import point_inputs

__all__ = ["Points", "Strands", "resident_strands"]


def resident_strands(ctx, scene: Scene) -> Strands:
    """`scene`'s strands on the GPU of `ctx`, uploaded on the scene's first GL render and
    kept for the later ones (module docstring)."""
    return cached(scene, f"GL strands in context {id(ctx)}", lambda: Strands(ctx, scene))


def _release(buffers: list) -> None:
    for b in buffers:
        b.release()


# Light-raster coordinates beyond this are clipped to it: far off any raster, and within float32.
FAR_OFF_RASTER = 1e30


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
        # Whether a render wrote Ω or V over their defaults (0 and 1), for the next render.
        self.omega_written = self.visibility_written = False
        buffers = [
            self.position,
            self.tangent,
            self.color,
            self.alpha,
            self.width,
            self.omega,
            self.visibility,
        ]
        # The buffers go with this object: dropped from the cache, or released at once.
        self._release = weakref.finalize(self, _release, [*buffers, *(b for b, _, _ in self.extra)])
        self._release.atexit = False  # at exit the context goes first, and its buffers with it

    def write_omega(self, omega: np.ndarray | None) -> None:
        """Ω per point for the camera pass (`float32[P]`); None: 0, no shadow."""
        if omega is not None or self.omega_written:
            values = np.zeros(self.count, "f4") if omega is None else omega
            self.omega.write(np.ascontiguousarray(values, "f4").tobytes())
        self.omega_written = omega is not None

    def write_visibility(self, visibility: np.ndarray | None) -> None:
        """The occluder's visibility V per point (`float32[P]`); None: 1, unoccluded."""
        if visibility is not None or self.visibility_written:
            values = np.ones(self.count, "f4") if visibility is None else visibility
            self.visibility.write(np.ascontiguousarray(values, "f4").tobytes())
        self.visibility_written = visibility is not None

    def screen_buffer(self, frame):
        """The strand points in the light's raster (`frame.xy`, `frame.depth`: the host's
        float64 projection, docs/model.md §7) as float32 `in_screen`, for a light pass's
        `vertex_array`; its caller releases it."""
        p = self.count
        # The clip fires for a point light at the hair's centre (near ≈ 1e-303: xy up to
        # 1e300, beyond float32); such a point lies far off the raster either way.
        xy = np.clip(frame.xy[:p], -FAR_OFF_RASTER, FAR_OFF_RASTER)
        screen = np.column_stack([xy, frame.depth[:p]]).astype("f4")
        return self.ctx.buffer(screen.tobytes() if screen.size else b"\0" * 12)

    def vertex_array(self, prog, index_buffer, screen=None):
        """The program's vertex array over `index_buffer`; `screen` (`screen_buffer`'s)
        for a light pass."""
        given = [] if screen is None else [(screen, "3f", "in_screen")]
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
                *given,
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
        self._release()


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
