"""Error against run time: one quality knob at a time, both renderers (docs/results.md §1).

`run_sweep(scene, out)` renders the scene at every value of every knob, with the JAX path
and the GL path, and measures each image against that path's converged reference: exact
shadows, exact ordering, the finest supersampling swept. Each finished point is appended
to `points.jsonl` at once, so an interrupted sweep resumes where it stopped; the report
(`hairjax/tools/_sweep_report.py`) is built from that file.

Knobs (each point changes one; the others keep the scene's settings):
- `shadows`: the shadow method (every registered one, docs/model.md §7), keeping the
  scene's options that it takes;
- `maps`: number of opacity maps N; `map_resolution`: the light's raster in texels;
  `layers`: a method's layer count, for one registered with a `layers` field (each only
  where the scene's method has the field);
- `bins`: visibility bins, and `exact` (a full depth sort);
- `width`: ribbons f× as wide with opacity a/f (the same opacity per unit length until a/f
  reaches 1), against the reference at f = 1;
- `supersampling`: s × s renders on sub-pixel offsets, averaged (`hairjax.supersample`).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .._progress import Progress, progress_of
from .._scene._scene import Scene
from ._knobs import KNOBS, SHADOW_KNOBS, SHADOW_OPTIONS, knob_scene, method_options, reference_config
from ._measure import (
    PATHS,
    check_run,
    errors,
    measure,
    path_reference,
    renderer,
    scene_digest,
    target_reference,
)
from ._sweep_store import append_point, check_config, load_points, rewrite_points

__all__ = ["PATHS", "run_sweep", "load_points", "scene_digest", "sweep_knobs"]


def sweep_knobs(scene: Scene, knobs: dict) -> dict:
    """The knobs that turn something in `scene`: a scene without shadows has no shadow
    knobs, and a knob setting a field its shadow method lacks (`maps` of exact shadows)
    is dropped."""
    takes = method_options(scene.shadows.method)
    return {
        k: v
        for k, v in knobs.items()
        if (scene.shadows.casts or k not in SHADOW_KNOBS) and (k not in SHADOW_OPTIONS or k in takes)
    }


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
    repeats = check_run(knobs, paths, repeats)
    given = None if target is None else target_reference(scene, target)
    knobs = sweep_knobs(scene, knobs)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    config = {
        "scene": scene.name,
        "scene_digest": scene_digest(scene),
        "repeats": repeats,
        "reference": reference_config(scene, knobs) if given is None else {"target": given["digest"]},
        "knobs": {k: list(v) for k, v in knobs.items()},
        "paths": list(paths),
        "size": [scene.camera.width, scene.camera.height],
    }
    check_config(out, config, restart, "sweep.json", "points.jsonl", others=("joint.json",))

    finished = load_points(out)
    rewrite_points(out, finished)
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
                runs[path] = renderer(path)
                if given is None:
                    references[path] = path_reference(out, path, runs[path], scene, knobs)
                    report(count, total, f"{path} reference")
                else:
                    references[path] = given
            label = f"{path} {knob} = {value}"
            try:
                variant, s = knob_scene(scene, knob, value)
                image, omega, median, times = measure(runs[path], variant, s, repeats)
            except ValueError as err:
                # A setting the scene or the renderer refuses (e.g. JAX's cap on
                # opacity-map memory) is recorded as skipped, with the reason, and the
                # sweep goes on.
                append_point(out, {"path": path, "knob": knob, "value": value, "skipped": str(err)})
                count += 1
                report(count, total, f"{label} (skipped)")
                continue
            point = {
                "path": path,
                "knob": knob,
                "value": value,
                "time_s": median,
                "times": times,
                **errors(image, omega, references[path], kappa),
            }
            append_point(out, point)
            count += 1
            report(count, total, label)
    return load_points(out)
