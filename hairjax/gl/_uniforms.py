"""Uniform values for the GL programs: moderngl's Python types from NumPy, and the uniform
sets several passes share (a view of docs/model.md §2 / §7, the light of §3, the light's
passes of §7)."""

from __future__ import annotations

import numpy as np

from .._geometry._shadows import LightFrame
from .._scene._scene import Scene

__all__ = ["light_pass_uniforms", "light_uniforms", "set_uniforms", "vec", "view_uniforms"]


def set_uniforms(prog, **values) -> None:
    """Set uniforms; names the compiler removed as unused are skipped."""
    for name, value in values.items():
        try:
            uniform = prog[name]
        except KeyError:
            continue
        uniform.value = value


def vec(v) -> tuple:
    """A vector as the tuple of Python floats a moderngl uniform takes."""
    return tuple(float(x) for x in np.asarray(v).ravel())


def view_uniforms(prefix: str, view) -> dict:
    """The `View` struct of model.glsl (docs/model.md §2, §7) named `prefix`."""
    return {
        f"{prefix}.origin": vec(view.origin),
        f"{prefix}.forward": vec(view.forward),
        f"{prefix}.right": vec(view.right),
        f"{prefix}.up": vec(view.up),
        f"{prefix}.focal": float(view.focal),
        f"{prefix}.center": (float(view.cx), float(view.cy)),
        # Fires for orthographic (directional-light) views: near = −inf, unused there.
        f"{prefix}.near": float(view.near) if np.isfinite(view.near) else -1e30,
        f"{prefix}.perspective": bool(view.perspective),
    }


def light_uniforms(scene: Scene) -> dict:
    """The light (docs/model.md §3): the unit vector towards a directional light, or a
    point light's position, and its colour."""
    light = scene.light
    if light.kind == "directional":
        d = -np.asarray(light.direction, dtype=np.float64)
        vector, point = d / np.linalg.norm(d), False
    else:
        vector, point = np.asarray(light.position, dtype=np.float64), True
    return {"light_vector": vec(vector), "point_light": point, "light_rgb": vec(light.color)}


def light_pass_uniforms(scene: Scene, frame: LightFrame) -> dict:
    """The ribbon programs drawn from the light (docs/model.md §7): its raster, unshaded."""
    r = scene.shadows.resolution
    return dict(
        raster_size=(float(r), float(r)),
        shade=False,
        given_screen=True,  # the strands' `screen_buffer` (`Strands.vertex_array`)
        world_width=scene.strands.width_units == "world",
        light_perspective=bool(frame.view.perspective),
        resolution=r,
        **view_uniforms("view", frame.view),
    )
