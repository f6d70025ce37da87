"""Error against run time: one quality knob at a time, both renderers (docs/results.md §1).

`run_sweep(scene, out)` renders the scene at every value of every knob, with the JAX path
and the GL path, and measures each image against that path's converged reference: exact
shadows, exact ordering, the finest supersampling swept. Each finished point is appended
to `points.jsonl` at once, so an interrupted sweep resumes where it stopped; the report
(`hairjax/tools/_sweep_report.py`) is built from that file.

Knobs (each point changes one; the others keep the scene's settings):
- `maps`: number of opacity maps N; `map_resolution`: their size in texels;
- `bins`: visibility bins, and `exact` (a full depth sort);
- `width`: ribbons f× as wide with opacity a/f (the same opacity per unit length until a/f
  reaches 1), against the reference at f = 1;
- `supersampling`: s × s renders on sub-pixel offsets, averaged (`hairjax.supersample`).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import jax
import numpy as np

from .._io._files import atomic_path, write_json, write_text
from .._progress import Progress, progress_of
from .._scene._scene import Scene
from .._supersample import supersample
from ._compare import check_repeats, image_stats
from ._knobs import KNOBS, SHADOW_KNOBS, SweepError, knob_scene, reference_scene

__all__ = ["PATHS", "run_sweep", "load_points", "scene_digest"]

PATHS = ("jax", "gl")


def _renderer(path: str) -> Callable[[Scene], tuple[np.ndarray, np.ndarray | None]]:
    """A function rendering a scene with one path to (image [H, W, 4], Ω per point)."""
    if path == "jax":
        import jax

        from .._cache import forget
        from .._geometry._stage import geometry_stage
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


def _measure(run, scene: Scene, s: int, repeats: int):
    """(image, Ω, median seconds, all seconds): one untimed warm-up (compilation, shader
    builds), then `repeats` timed renders (none: the median is NaN)."""
    omega: dict[str, np.ndarray | None] = {}

    def image_of(sc):
        image, om = run(sc)
        omega.setdefault("first", om)
        return image

    image = supersample(image_of, scene, s)
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        supersample(lambda sc: run(sc)[0], scene, s)
        times.append(time.perf_counter() - start)
    return np.asarray(image), omega["first"], float(np.median(times)) if times else float("nan"), times


def _errors(image: np.ndarray, omega, reference: dict, kappa: float) -> dict:
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


def load_points(out: Path) -> list[dict]:
    """The finished points of the sweep in `out` (a line cut short by an interruption is
    ignored: it is redone on resume)."""
    path = Path(out) / "points.jsonl"
    if not path.exists():
        return []
    points = []
    for line in path.read_text().splitlines():
        try:
            points.append(json.loads(line))
        except json.JSONDecodeError:
            continue  # fires only for a last line cut short by a kill
    return points


def _append(out: Path, point: dict) -> None:
    with open(Path(out) / "points.jsonl", "a") as f:
        f.write(json.dumps(point) + "\n")
        f.flush()
        os.fsync(f.fileno())


def _rewrite(out: Path, points: list[dict]) -> None:
    write_text(Path(out) / "points.jsonl", "".join(json.dumps(p) + "\n" for p in points))


def _check_config(out: Path, config: dict, restart: bool) -> None:
    path = out / "sweep.json"
    if path.exists() and not restart:
        old = json.loads(path.read_text())
        same = {k: old.get(k) for k in ("scene_digest", "repeats", "reference")}
        if same != {k: config[k] for k in same}:
            raise SweepError(
                f"{out} holds a sweep of other settings ({old.get('scene')}, "
                f"repeats {old.get('repeats')}); choose another --out or pass --restart"
            )
    if restart:
        for name in ("points.jsonl", *[f"reference_{p}.npz" for p in PATHS]):
            (out / name).unlink(missing_ok=True)
    write_json(path, config)


def _reference(out: Path, path: str, run, scene: Scene, knobs: dict, repeats: int) -> dict:
    """The path's converged reference, rendered once and kept in `out`."""
    file = out / f"reference_{path}.npz"
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
    image, omega, _, _ = _measure(run, ref_scene, s, 0)
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


def _target_reference(scene: Scene, target) -> dict:
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


def run_sweep(
    scene: Scene,
    out,
    *,
    knobs: dict | None = None,
    paths: Sequence[str] = PATHS,
    repeats: int = 3,
    restart: bool = False,
    progress: Progress | bool | None = None,
    target=None,
) -> list[dict]:
    """Sweep `knobs` (name → values; default `KNOBS`) for `paths` and return all points.

    A point is a dict: path, knob, value, and either `skipped` (why the renderer refused
    the setting) or rmse, max_abs, rel_rmse (RMSE over the reference's
    peak), tau_rmse and tau_max (per-point τ = exp(−κΩ) against the reference's, None
    without shadows), time_s (median of `repeats`), times. Points already in `out` are
    kept, not redone.

    `progress(done, total, message)` (`hairjax._progress`) after each point, `total` all
    the sweep's points and `done` counting those a resumed sweep found finished: its first
    call, "resuming: N of M points already done", has done = N. Each path's reference render
    is reported too, with `done` unchanged. (True and False, the older flags, are taken
    for one release: True draws `reporter("sweep")`.)

    `target`: an `[H, W, 3|4]` image (e.g. `reference_image`'s physically based one) that
    every point of both paths is measured against instead of each path's converged
    reference: the error then includes the model's own (docs/results.md). No reference is
    rendered, and tau_rmse and tau_max are None."""
    knobs = dict(KNOBS if knobs is None else knobs)
    for k in knobs:
        if k not in KNOBS:
            raise SweepError(f"unknown knob {k!r}; knobs: {', '.join(KNOBS)}")
    for p in paths:
        if p not in PATHS:
            raise SweepError(f"unknown path {p!r}; paths: {', '.join(PATHS)}")
    try:
        repeats = check_repeats(repeats)
    except ValueError as err:
        raise SweepError(str(err)) from None
    given = None if target is None else _target_reference(scene, target)
    if not scene.shadows.casts:
        # A scene without shadows has no shadow knobs to turn.
        knobs = {k: v for k, v in knobs.items() if k not in SHADOW_KNOBS}
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    config = {
        "scene": scene.name,
        "scene_digest": scene_digest(scene),
        "repeats": repeats,
        "reference": (
            {
                "shadows": ("none" if not scene.shadows.casts else f"exact at {scene.shadows.resolution}²"),
                "ordering": "exact",
                "supersampling": int(max(knobs.get("supersampling", (1,)))),
            }
            if given is None
            else {"target": given["digest"]}
        ),
        "knobs": {k: list(v) for k, v in knobs.items()},
        "paths": list(paths),
        "size": [scene.camera.width, scene.camera.height],
    }
    _check_config(out, config, restart)

    finished = load_points(out)
    _rewrite(out, finished)  # drops a line cut short, so the next append starts a fresh line
    done = {(p["path"], p["knob"], json.dumps(p["value"])) for p in finished}
    planned = [(path, knob, value) for path in paths for knob, values in knobs.items() for value in values]
    todo = [point for point in planned if (point[0], point[1], json.dumps(point[2])) not in done]
    kappa = float(np.asarray(scene.params.kappa))
    total, count = len(planned), len(planned) - len(todo)
    with progress_of(progress, "sweep") as report:
        if count:
            report(count, total, f"resuming: {count} of {total} points already done")
        runs = {}
        references = {}
        for path, knob, value in todo:
            if path not in runs:
                runs[path] = _renderer(path)
                if given is None:
                    references[path] = _reference(out, path, runs[path], scene, knobs, repeats)
                    report(count, total, f"{path} reference")
                else:
                    references[path] = given
            variant, s = knob_scene(scene, knob, value)
            label = f"{path} {knob} = {value}"
            try:
                image, omega, median, times = _measure(runs[path], variant, s, repeats)
            except ValueError as err:
                # A setting the renderer refuses (e.g. JAX's cap on opacity-map memory) is
                # recorded as skipped, with the reason, and the sweep goes on.
                _append(out, {"path": path, "knob": knob, "value": value, "skipped": str(err)})
                count += 1
                report(count, total, f"{label} (skipped)")
                continue
            point = {
                "path": path,
                "knob": knob,
                "value": value,
                "time_s": median,
                "times": times,
                **_errors(image, omega, references[path], kappa),
            }
            _append(out, point)
            count += 1
            report(count, total, label)
    return load_points(out)
