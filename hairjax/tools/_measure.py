"""One point of the settings search (docs/results.md §1): render a setting with one path,
time it and measure its error against that path's reference.

The search (`_search.py`) measures every point of the one-knob sweep and of the joint
search here: the same reference per path (exact shadows at the scene's map resolution,
exact ordering, the finest supersampling searched), the same relative RMSE (RMSE over the
reference's peak), the same timing (the median of `repeats` renders after an untimed
warm-up).
"""

from __future__ import annotations

import dataclasses
import hashlib
import time
from collections.abc import Callable
from pathlib import Path

import jax
import numpy as np

from .._io._files import atomic_path
from .._scene._scene import Scene
from .._supersample import supersample
from ._compare import check_repeats, image_stats, timed_calls
from ._knobs import KNOBS, SweepError, reference_scene

__all__ = ["PATHS", "renderer", "measure", "errors", "path_reference", "target_reference", "scene_digest"]

PATHS = ("jax", "gl")


def check_run(knobs, paths, repeats: int, *, empty_values: bool = True) -> int:
    """The knob names, paths and repeats of a sweep or a joint search, checked before any
    work (`SweepError`, one line naming the bad one); the repeats as an int.
    `empty_values=False` also refuses a knob given no values."""
    for k, values in knobs.items():
        if k not in KNOBS:
            raise SweepError(f"unknown knob {k!r}; knobs: {', '.join(KNOBS)}")
        if not empty_values and not values:
            raise SweepError(f"knob {k!r} has no values")
    for p in paths:
        if p not in PATHS:
            raise SweepError(f"unknown path {p!r}; paths: {', '.join(PATHS)}")
    try:
        return check_repeats(repeats)
    except ValueError as err:
        raise SweepError(str(err)) from None


Renderer = Callable[[Scene], tuple[np.ndarray, np.ndarray | None]]


def renderer(path: str) -> Renderer:
    """A function rendering a scene with one path to (image [H, W, 4], Ω per point)."""
    if path == "jax":
        from .._cache import forget
        from .._geometry_stage._stage import geometry_stage
        from .._render import render

        def run(scene):
            forget(scene)  # time the whole render, not a cached geometry stage
            image = np.asarray(jax.block_until_ready(render(scene)))
            omega = geometry_stage(scene).omega
            forget(scene)  # the sweep renders hundreds of scenes: keep no geometry alive
            return image, None if omega is None else np.asarray(omega)

        return run
    if path == "gl":
        from ..gl import render_gl

        def run(scene):
            result = render_gl(scene)
            return result.image, result.omega

        return run
    raise SweepError(f"unknown path {path!r}; paths: {', '.join(PATHS)}")


def measure(run: Renderer, scene: Scene, s: int, repeats: int):
    """(image, Ω, median seconds, all seconds): one untimed warm-up (compilation, shader
    builds), then `repeats` timed renders (`timed_calls`; none: the median is NaN)."""
    omega: dict[str, np.ndarray | None] = {}

    def image_of(sc):
        image, om = run(sc)
        omega.setdefault("first", om)
        return image

    def render():
        return supersample(image_of, scene, s)

    if not repeats:  # a cost model charges the setting's time: the error's render only
        return np.asarray(render()), omega["first"], float("nan"), []
    timed = timed_calls(render, repeats)
    return np.asarray(timed.last), omega["first"], timed.median_s, timed.runs_s


def errors(image: np.ndarray, omega, reference: dict, kappa: float) -> dict:
    """rmse, max_abs, rel_rmse (RMSE over the reference's peak) of the colour channels, and
    tau_rmse, tau_max of the per-point transmittance (None without Ω on either side)."""
    stats = image_stats(image[..., :3], reference["image"][..., :3])
    out = {
        "rmse": stats["rmse"],
        "max_abs": stats["max_abs"],
        "rel_rmse": stats["rmse"] / reference["peak"],
        "tau_rmse": None,
        "tau_max": None,
    }
    if omega is not None and reference["omega"] is not None:
        # τ = exp(−κΩ) (`transmittance`, §7) in float64 NumPy: the error measure stays
        # outside JAX's working precision.
        dtau = np.exp(-kappa * np.asarray(omega, np.float64)) - np.exp(-kappa * reference["omega"])
        out["tau_rmse"] = float(np.sqrt(np.mean(dtau**2)))
        out["tau_max"] = float(np.abs(dtau).max())
    return out


def scene_digest(scene: Scene) -> str:
    """A hash of everything that changes the image, to tell one sweep's folder from another's."""
    h = hashlib.sha256()
    s = scene.strands
    occ = scene.occluder
    mesh = (occ.vertices, occ.triangles) if occ is not None and occ.kind == "mesh" else ()
    for a in (s.points, s.offsets, s.alpha, s.width, s.color, *mesh):
        if a is not None:
            h.update(np.ascontiguousarray(a).tobytes())
    h.update(
        repr(
            (
                scene.camera,
                scene.light,
                scene.shading.name,
                scene.shadows,
                scene.ordering,
                scene.occluder,
                scene.background,
            )
        ).encode()
    )
    # The model's configuration (a table size, §17's maps) and its parameters' values.
    h.update(
        repr(
            [
                (f.name, getattr(scene.shading, f.name))
                for f in dataclasses.fields(scene.shading)
                if f.name != "params"
            ]
        ).encode()
    )
    for leaf in jax.tree_util.tree_leaves(scene.params):
        h.update(np.asarray(leaf, np.float64).tobytes())
    if scene.streaks is not None:  # §16
        h.update(repr(scene.streaks).encode())
    return h.hexdigest()[:16]


def path_reference(out: Path, path: str, run: Renderer, scene: Scene, knobs: dict) -> dict:
    """The path's converged reference (`reference_scene`), rendered once and kept in
    `out` as reference_PATH.npz: image, Ω, peak, the render's seconds."""
    file = Path(out) / f"reference_{path}.npz"
    if file.exists():
        data = np.load(file)
        omega = data["omega"] if data["omega"].size else None
        return {
            "image": data["image"],
            "omega": omega,
            "peak": float(data["peak"]),
            "time_s": float(data["time_s"]),
        }
    ref_scene, s = reference_scene(scene, knobs)
    # Rendered once, untimed beyond that one run: its image is what the points need, and at
    # s² exact-shadow renders it is the sweep's most expensive setting.
    start = time.perf_counter()
    image, omega, _, _ = measure(run, ref_scene, s, 0)
    median = time.perf_counter() - start
    image = image.astype(np.float64)
    # The peak normalises the relative RMSE; a black reference would make every error
    # infinite, so it fires only for an empty scene, which is refused.
    peak = float(image[..., :3].max())
    if not peak > 0:
        raise SweepError("the reference image is black: nothing to measure errors against")
    omega = None if omega is None else np.asarray(omega, np.float64)
    with atomic_path(file, ".npz") as tmp:
        with open(tmp, "wb") as f:
            np.savez(f, image=image, omega=np.zeros(0) if omega is None else omega, peak=peak, time_s=median)
    return {"image": image, "omega": omega, "peak": peak, "time_s": median}


def target_reference(scene: Scene, target) -> dict:
    """A given target image as every path's reference: checked against the scene's size
    (SweepError before any work), its peak for the relative RMSE, no Ω."""
    image = np.asarray(target, np.float64)
    size = (scene.camera.height, scene.camera.width)
    if image.ndim != 3 or image.shape[2] not in (3, 4) or image.shape[:2] != size:
        raise SweepError(
            f"the target is {'x'.join(map(str, image.shape))}, the scene renders "
            f"{size[1]}x{size[0]}: a target must be [H, W, 3 or 4] at the scene's size"
        )
    if not np.all(np.isfinite(image[..., :3])):
        raise SweepError("the target has NaN or infinite pixels")
    peak = float(image[..., :3].max())
    if not peak > 0:  # the relative RMSE divides by it
        raise SweepError("the target image is black: nothing to measure errors against")
    digest = hashlib.sha256(np.ascontiguousarray(image).tobytes()).hexdigest()[:16]
    return {"image": image, "omega": None, "peak": peak, "time_s": float("nan"), "digest": digest}
