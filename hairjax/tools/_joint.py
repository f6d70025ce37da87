"""The joint search of the settings space, per renderer (docs/results.md, "Joint search").

`run_joint(scene, out)` searches the combinations of the sweep's knobs (`JOINT_KNOBS`: the
shadow method and its options, bins, ribbon width, supersampling) for the Pareto front of
error against run time, with the JAX path and the GL path, by the search of `_pareto.py`.
Each point is measured as the one-knob sweep measures it (`_measure.py`: the same
reference per path, relative RMSE, the median of `repeats` timed renders after a warm-up)
and appended to `joint.jsonl` as it finishes. A rerun replays the stored points without
rendering them (the search is deterministic in them) and goes on where it stopped. The
report (`_joint_report.py`) is built from the points."""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import numpy as np

from .._progress import Progress, progress_of
from .._scene._scene import Scene
from ._knob_space import KnobSpace, knob_space, setting_key
from ._knobs import JOINT_KNOBS, reference_config, settings_scene
from ._measure import PATHS, check_run, errors, measure, path_reference, renderer, scene_digest
from ._pareto import SearchConfig, pareto_search
from ._sweep_store import append_point, check_config, load_points, rewrite_points

__all__ = ["run_joint", "load_joint", "POINTS_FILE", "CONFIG_FILE"]

POINTS_FILE, CONFIG_FILE = "joint.jsonl", "joint.json"
Cost = Callable[[Mapping], float]


def load_joint(out) -> list[dict]:
    """The finished points of the joint search in `out`, every path's."""
    return load_points(out, POINTS_FILE)


class _Evaluator:
    """`evaluate(setting)` for the search, for one path: a point stored in `out` is
    returned as it is (`replayed` is then True), a new one is measured and appended. The
    renderer and the reference are made at the first point that needs a render, so a
    search resumed from a finished folder renders nothing."""

    def __init__(self, out: Path, path: str, scene: Scene, space: KnobSpace, timing: tuple, report: Progress):
        self.out, self.path, self.scene, self.space, self.report = out, path, scene, space, report
        self.repeats, self.cost = timing  # (repeats, cost model or None)
        self.stored = {setting_key(p["settings"]): p for p in load_joint(out) if p["path"] == path}
        self.kappa = float(np.asarray(scene.params.kappa))
        self.made: dict = {}
        self.calls, self.replayed = 0, False

    def _reference(self) -> dict:
        if not self.made:
            done = self.calls - 1  # the points before this one; the reference is not one
            self.report(done, done + 1, f"{self.path} reference")
            self.made["run"] = renderer(self.path)
            self.made["reference"] = path_reference(
                self.out, self.path, self.made["run"], self.scene, dict(self.space.knobs)
            )
        return self.made["reference"]

    def __call__(self, setting: dict) -> dict:
        self.calls += 1
        key = setting_key(setting)
        self.replayed = key in self.stored
        if self.replayed:
            return self.stored[key]
        reference = self._reference()
        start = time.perf_counter()
        try:
            variant, s = settings_scene(self.scene, setting)
            repeats = 0 if self.cost else self.repeats  # a cost model: the error's render only
            image, omega, median, times = measure(self.made["run"], variant, s, repeats)
        except ValueError as err:
            # A setting the scene or the renderer refuses (e.g. JAX's cap on opacity-map
            # memory) is recorded as skipped, with the reason, and the search goes on.
            point: dict = {"path": self.path, "settings": setting, "skipped": str(err)}
        else:
            point = {
                "path": self.path,
                "settings": setting,
                "time_s": median if self.cost is None else float(self.cost(setting)),
                "times": times,
                "wall_s": time.perf_counter() - start,  # warm-up and timed renders: the point's cost
                **errors(image, omega, reference, self.kappa),
            }
        append_point(self.out, point, POINTS_FILE)
        self.stored[key] = point
        return point


def run_joint(
    scene: Scene,
    out,
    *,
    knobs: Mapping[str, Sequence] | None = None,
    paths: Sequence[str] = PATHS,
    repeats: int = 3,
    search: SearchConfig | None = SearchConfig(),
    restart: bool = False,
    progress: Progress | None = None,
    cost: Cost | None = None,
) -> list[dict]:
    """Search `knobs` (name → values, cheapest first; default `JOINT_KNOBS`) jointly for
    each of `paths`, and return the points evaluated, every path's, in order.

    A point is a dict: path, settings (knob → value: the knobs of its shadow method, the
    others), and either `skipped` or the one-knob sweep's measures (`run_sweep`): time_s,
    times, rmse, max_abs, rel_rmse, tau_rmse, tau_max; and wall_s, the seconds its
    measurement took (warm-up and timed renders). `search=None` evaluates the full
    grid instead, every combination (to check the search on a small space). `cost`
    (tests): the seconds charged to a setting, instead of timed renders (only the warm-up
    render, for the error, is made). `progress(done, total, message)` after each point."""
    knobs = dict(JOINT_KNOBS if knobs is None else knobs)
    repeats = check_run(knobs, paths, repeats, empty_values=False)
    space = knob_space(scene, knobs)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    config = {
        "scene": scene.name,
        "scene_digest": scene_digest(scene),
        "repeats": repeats,
        "timing": "measured" if cost is None else "cost model",
        "reference": reference_config(scene, space.knobs),
        "space": space.to_json(),
        "search": None if search is None else dataclasses.asdict(search),
        "paths": list(paths),
        "size": [scene.camera.width, scene.camera.height],
    }
    check_config(out, config, restart, CONFIG_FILE, POINTS_FILE, others=("sweep.json",), keys=("timing",))
    rewrite_points(out, load_joint(out), POINTS_FILE)
    evaluated = []
    with progress_of(progress, "joint search") as report:
        for path in paths:
            evaluate = _Evaluator(out, path, scene, space, (repeats, cost), report)
            if evaluate.stored:
                n = len(evaluate.stored)
                report(0, n, f"{path}: resuming, {n} points already measured")

            def path_report(done: int, total: int, message: str = "", evaluate=evaluate) -> None:
                if not evaluate.replayed:  # a resumed search replays its points in a moment
                    report(done, total, f"{evaluate.path} {message}")

            if search is None:
                grid = list(space.grid())
                for i, setting in enumerate(grid):
                    evaluated.append(evaluate(setting))
                    path_report(i + 1, len(grid), str(setting))
            else:
                evaluated += pareto_search(space, evaluate, search, path_report)
    return evaluated
