"""The GL side of the shadow methods: each method's pass, registered under the method's
name (`AbstractShadowMethod.method`, hairjax/_geometry/_shadows/), so that a new method is one GL
module with `@register_gl_shadow_pass(name)` beside its JAX module.

A pass is `fn(ctx, progs, scene, strands, frame, points, drawing) -> Ω` with Ω per point
of `points` (strand points, then the occluder's receivers), float32; `drawing` (a
`PassDrawing`) says how it draws.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

__all__ = ["PassDrawing", "register_gl_shadow_pass", "gl_shadow_pass"]


class PassDrawing(NamedTuple):
    """How a render's shadow pass draws: `clip_slices`, only the segments whose depth range
    meets a slice (kim-2003 §4.2; a pass without slices ignores it), and the ribbons'
    `expansion` (`_ribbons.Ribbons`)."""

    clip_slices: bool = True
    expansion: str = "geometry-shader"


_PASSES: dict[str, Callable] = {}


def register_gl_shadow_pass(method: str) -> Callable[[Callable], Callable]:
    """Decorator: `fn` is the GL pass of shadow method `method`."""

    def register(fn: Callable) -> Callable:
        _PASSES[method] = fn
        return fn

    return register


def gl_shadow_pass(method: str) -> Callable:
    """The GL pass of shadow method `method`; `TypeError` if it has none."""
    try:
        return _PASSES[method]
    except KeyError:
        raise TypeError(f"shadow method {method!r} has no GL pass; GL has: {', '.join(_PASSES)}") from None
