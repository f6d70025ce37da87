"""The animated fur ball (wenzel-2002; docs/model.md §15).

The ball moves along a Lissajous path p(t) = a ⊙ sin(2π f t + φ) (t ∈ [0, 1) over one
loop, frame k of N at t = k/N, so the loop closes), offset by `hair.translate`. Its hairs
are grown every frame with wenzel-2002's joint rule, d ← normalise(d + gravity + inertia),
where the inertia vector comes from the second derivative of the motion: in the ball's
accelerating frame a hair feels −m·p'', so inertia = −k·p''(t) and hairs bend away from
the acceleration (wenzel-2002 says only "the 2nd derivative"; the sign is d'Alembert's).
The ball translates without turning, so every hair end has the ball's acceleration.
"""

from __future__ import annotations

import copy
import dataclasses
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ._errors import SceneError
from ._progress import Progress, progress_of
from ._scene._file import load_scene, scene_from_dict, scene_tables, with_overrides
from ._scene._scene import Scene
from ._scene._table import Table, build

__all__ = [
    "Motion",
    "Animation",
    "load_animation",
    "path_position",
    "path_acceleration",
    "inertia_vector",
    "write_frames",
]


def _vec3(name: str, value) -> tuple[float, float, float]:
    arr = np.asarray(value, dtype=np.float64)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise SceneError(f"{name} must be 3 finite numbers, got {value!r}")
    return float(arr[0]), float(arr[1]), float(arr[2])


@dataclasses.dataclass(frozen=True)
class Motion:
    """The ball's path and how strongly it bends the hair.

    **Fields:** `amplitude` a and `frequency` f (cycles per loop) per axis, `phase` φ per
    axis in degrees, `inertia` k ≥ 0 (inertia vector = −k·p''), `frames` per loop."""

    amplitude: tuple[float, float, float] = (0.5, 0.25, 0.0)
    frequency: tuple[float, float, float] = (1.0, 2.0, 0.0)
    phase: tuple[float, float, float] = (0.0, 0.0, 0.0)
    inertia: float = 0.004
    frames: int = 24

    def __post_init__(self):
        for key in ("amplitude", "frequency", "phase"):
            object.__setattr__(self, key, _vec3(f"animation.{key}", getattr(self, key)))
        if not (np.isfinite(self.inertia) and self.inertia >= 0):
            raise SceneError(f"animation.inertia must be >= 0, got {self.inertia!r}")
        f = self.frames
        if isinstance(f, bool) or int(f) != f or f < 1:
            raise SceneError(f"animation.frames must be an integer >= 1, got {f!r}")
        object.__setattr__(self, "inertia", float(self.inertia))
        object.__setattr__(self, "frames", int(f))


def _angle(motion: Motion, t: float) -> np.ndarray:
    return 2 * np.pi * np.asarray(motion.frequency) * t + np.radians(motion.phase)


def path_position(motion: Motion, t: float) -> np.ndarray:
    """p(t) = a ⊙ sin(2π f t + φ), `float64[3]` (relative to `hair.translate`)."""
    return np.asarray(motion.amplitude) * np.sin(_angle(motion, t))


def path_acceleration(motion: Motion, t: float) -> np.ndarray:
    """p''(t) = −a ⊙ (2π f)² ⊙ sin(2π f t + φ), `float64[3]` (per loop²)."""
    omega = 2 * np.pi * np.asarray(motion.frequency)
    return -np.asarray(motion.amplitude) * omega**2 * np.sin(_angle(motion, t))


def inertia_vector(motion: Motion, t: float) -> np.ndarray:
    """wenzel-2002's inertia vector at time t: −k·p''(t), `float64[3]`."""
    return -motion.inertia * path_acceleration(motion, t)


@dataclasses.dataclass(frozen=True)
class Animation:
    """A scene file with an `[animation]` table: `scene(t)` is the frame at time t."""

    data: dict
    base_dir: Path
    name: str
    source: str
    motion: Motion

    def scene(self, t: float) -> Scene:
        """The scene at loop time t: the fur ball regrown with its hair.inertia plus the
        path's inertia, and moved by p(t)."""
        data = copy.deepcopy(self.data)
        data.pop("animation", None)
        hair = data["hair"]
        inertia = np.add(hair.get("inertia", (0.0, 0.0, 0.0)), inertia_vector(self.motion, t))
        translate = np.add(hair.get("translate", (0.0, 0.0, 0.0)), path_position(self.motion, t))
        hair["inertia"] = [float(x) for x in inertia]
        hair["translate"] = [float(x) for x in translate]
        return scene_from_dict(data, self.base_dir, self.name, source=self.source)


def load_animation(path, overrides: Mapping[str, Any] | None = None) -> Animation:
    """Read a scene file for `hairjax animate`: a fur ball (`hair.source = "furball"`) and
    an optional `[animation]` table (docs/scenes.md; absent keys take `Motion`'s defaults).
    `overrides`: `"table.key" → value`, as `load_scene`'s.

    **Raises:** `SceneError`, naming the file and the key, as `load_scene`."""
    path = Path(path)
    load_scene(path, overrides)  # every check of the still scene, with its messages
    with open(path, "rb") as f:
        data = tomllib.load(f)
    where = str(path)
    data = with_overrides(data, overrides or {}, where)
    if data["hair"].get("source") != "furball":
        raise SceneError(
            f"{where}: hair.source must be 'furball' to animate (wenzel-2002's fur "
            f"ball), got {data['hair'].get('source')!r}"
        )
    table = Table("animation", data.get("animation", {}), where, scene_tables()["animation"])
    kwargs = {
        k: v
        for k, v in dict(
            amplitude=table.vec3("amplitude"),
            frequency=table.vec3("frequency"),
            phase=table.vec3("phase"),
            inertia=table.number("inertia", lo=0),
            frames=table.integer("frames", lo=1),
        ).items()
        if v is not None
    }
    motion = build(where, Motion, **kwargs)
    name = data.get("name", path.stem)
    return Animation(data, path.resolve().parent, name, where, motion)


def write_frames(
    animation: Animation,
    out_dir,
    frames: int | None = None,
    backend: str = "jax",
    png: bool = False,
    gif: bool = False,
    progress: Progress | bool | None = None,
) -> list[Path]:
    """Render the loop's frames into `out_dir`: `frame_0000.exr` … (linear float RGBA),
    with `png` also `frame_0000.png` … (8-bit sRGB), with `gif` also `animation.gif`.

    `frames` (default the file's `animation.frames`): frame k is at t = k/frames. Every
    file is written atomically. Returns the paths written.

    `progress(k + 1, frames, "frame k")` (`hairjax._progress`) after frame k is written.
    (True and False, the older flags, are taken for one release: True draws
    `reporter("frames")`.)"""
    from ._io._image import srgb8, write_image

    frames = animation.motion.frames if frames is None else frames
    if isinstance(frames, bool) or int(frames) != frames or frames < 1:
        raise ValueError(f"the number of frames must be an integer >= 1, got {frames!r}")
    if backend not in ("jax", "gl"):
        raise ValueError(f"backend must be 'jax' or 'gl', got {backend!r}")
    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise ValueError(f"{out_dir}: exists and is not a folder")
    out_dir.mkdir(parents=True, exist_ok=True)
    render = _renderer(backend)
    written, gif_frames = [], []
    with progress_of(progress, "frames") as report:
        for k in range(int(frames)):
            image = render(animation.scene(k / frames))
            written.append(write_image(out_dir / f"frame_{k:04d}.exr", image))
            if png:
                written.append(write_image(out_dir / f"frame_{k:04d}.png", image))
            if gif:
                gif_frames.append(srgb8(np.asarray(image, np.float64)[..., :3]))
            report(k + 1, int(frames), f"frame {k}")
    if gif:
        written.append(_write_gif(out_dir / "animation.gif", gif_frames))
    return written


def _renderer(backend: str):
    if backend == "gl":
        from .gl import render_gl

        return lambda scene: render_gl(scene).image
    from ._render import render

    return lambda scene: np.asarray(render(scene))


def _write_gif(path: Path, frames: list[np.ndarray], fps: float = 24.0) -> Path:
    """An endlessly looping GIF of 8-bit sRGB frames (Pillow; 256 colours per frame)."""
    from PIL import Image

    from ._io._files import atomic_path

    images = [Image.fromarray(f) for f in frames]
    with atomic_path(path, ".gif") as tmp:
        images[0].save(
            tmp, format="GIF", save_all=True, append_images=images[1:], duration=round(1000 / fps), loop=0
        )
    return path
