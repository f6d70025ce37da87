"""Supersampling: the box-filtered average of images rendered on a grid of sub-pixel offsets.

Each of the s × s images is a full render whose camera is shifted by an offset
((i + ½)/s − ½, (j + ½)/s − ½) pixels (`Camera.offset`), so the average samples every
pixel at s² positions spread evenly over its area. Ribbon widths stay in pixels and the
light's view does not move: only what the camera sees is resampled (docs/model.md §12).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import numpy as np

from ._scene._scene import Scene

__all__ = ["supersample", "supersample_offsets", "shifted"]


def supersample_offsets(s: int | float) -> list[tuple[float, float]]:
    """The s² camera offsets, in pixels, of an s × s supersampling grid (`s` a positive
    integer, also as a float such as 2.0; anything else is a ValueError)."""
    if isinstance(s, bool) or int(s) != s or s < 1:
        raise ValueError(f"supersampling must be a positive integer, got {s!r}")
    steps = (np.arange(int(s)) + 0.5) / s - 0.5
    return [(float(x), float(y)) for y in steps for x in steps]


def shifted(scene: Scene, offset: tuple[float, float]) -> Scene:
    """`scene` with its camera shifted by `offset` pixels."""
    return scene.replace(camera=dataclasses.replace(scene.camera, offset=offset))


def supersample(render: Callable[[Scene], Any], scene: Scene, s: int):
    """The mean of `render(shifted(scene, o))` over the s × s offsets. `render` returns an
    image (NumPy or JAX: the mean is taken with the array's own operators, so a JAX
    render stays differentiable)."""
    offsets = supersample_offsets(s)
    if offsets == [(0.0, 0.0)]:
        return render(scene)
    total = render(shifted(scene, offsets[0]))
    for o in offsets[1:]:
        total = total + render(shifted(scene, o))
    return total / len(offsets)
