"""The settings search (docs/results.md §1 and §7): error against run time over a space of
quality settings, per renderer, resumable. One engine; the one-knob sweep and the joint
search are two spaces it walks.

`run_search(scene, out, space, store)` evaluates settings of `space` with the JAX path and the GL
path: every setting of the space in order (`search=None`), or those the Pareto search of
`_pareto.py` asks for. Each point is measured against that path's converged reference
(`_measure.py`: exact shadows, exact ordering, the finest supersampling of the space) or a
given target image, and appended to the folder's store (`_store.py`) as it finishes. A
rerun replays the stored points without rendering them (the search is deterministic in
them) and goes on where it stopped. The report (`_report.py`) is built from the store.

- `run_sweep`: the one-knob sweep, every setting of a `OneKnobSpace` (each changes one
  knob from the scene's settings, the others keep them), in sweep.json and points.jsonl.
- `run_joint`: the joint search, the Pareto search of a `KnobSpace` (every combination of
  the knobs), in joint.json and joint.jsonl.

Knobs (`_knobs.py`):
- `shadows`: the shadow method (every registered one, docs/model.md §7), keeping the
  scene's options that it takes;
- `maps`: number of opacity maps N; `map_resolution`: the light's raster in texels;
  `layers`: a method's layer count, for one registered with a `layers` field (each only
  where the setting's method has the field);
- `bins`: visibility bins, and `exact` (a full depth sort);
- `width`: ribbons f× as wide with opacity a/f (the same opacity per unit length until a/f
  reaches 1), against the reference at f = 1;
- `supersampling`: s × s renders on sub-pixel offsets, averaged (`hairjax.supersample`).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import numpy as np

from .._progress import Progress, progress_of
from .._scene._scene import Scene
from ._knob_space import KnobSpace, OneKnobSpace, knob_space, one_knob_space, setting_key
from ._knobs import JOINT_KNOBS, KNOBS, reference_config, settings_scene
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
from ._pareto import SearchConfig, pareto_search
from ._store import JOINT_STORE, SWEEP_STORE, Store

__all__ = ["PATHS", "run_search", "run_sweep", "run_joint", "Cost"]

Cost = Callable[[Mapping], float]
Space = KnobSpace | OneKnobSpace


@dataclasses.dataclass
class _Run:
    """What every point of one run shares: `target`, a given target image's reference
    (`target_reference`) that every path is measured against, or None for each path's own;
    `cost`, seconds charged to a setting instead of timed renders, or None."""

    scene: Scene
    out: Path
    space: Space
    store: Store
    repeats: int
    cost: Cost | None
    target: dict | None
    report: Progress


class _Evaluator:
    """`evaluate(setting)` for one path: a point stored in the folder is returned as it is
    (`replayed` is then True), a new one is measured and appended. The renderer and the
    reference are made at the first point that needs a render, so a run resumed from a
    finished folder renders nothing; `position()` is the (done, total) its progress line
    about the reference shows."""

    def __init__(self, run: _Run, path: str, stored: list[dict], position: Callable[[], tuple[int, int]]):
        self.run, self.path, self.position = run, path, position
        self.stored = {setting_key(p["settings"]): p for p in stored if p["path"] == path}
        self.kappa = float(np.asarray(run.scene.params.kappa))
        self.made: dict = {}
        self.replayed = False

    def _reference(self) -> dict:
        if not self.made:
            self.made["run"] = renderer(self.path)
            if self.run.target is not None:
                self.made["reference"] = self.run.target
            else:
                self.run.report(*self.position(), f"{self.path} reference")
                knobs = dict(self.run.space.knobs)
                self.made["reference"] = path_reference(
                    self.run.out, self.path, self.made["run"], self.run.scene, knobs
                )
        return self.made["reference"]

    def __call__(self, setting: dict) -> dict:
        key = setting_key(setting)
        self.replayed = key in self.stored
        if not self.replayed:
            self.stored[key] = self.run.store.append(self.run.out, self._measure(setting))
        return self.stored[key]

    def _measure(self, setting: dict) -> dict:
        reference = self._reference()
        cost = self.run.cost
        start = time.perf_counter()
        try:
            variant, s = settings_scene(self.run.scene, setting)
            repeats = 0 if cost else self.run.repeats  # a cost model: the error's render only
            image, omega, median, times = measure(self.made["run"], variant, s, repeats)
        except ValueError as err:
            # A setting the scene or the renderer refuses (e.g. JAX's cap on opacity-map
            # memory) is recorded as skipped, with the reason, and the run goes on.
            return {"path": self.path, "settings": setting, "skipped": str(err)}
        return {
            "path": self.path,
            "settings": setting,
            "time_s": median if cost is None else float(cost(setting)),
            "times": times,
            "wall_s": time.perf_counter() - start,  # warm-up and timed renders: the point's cost
            **errors(image, omega, reference, self.kappa),
        }


def run_search(
    scene: Scene,
    out,
    space: Space,
    store: Store,
    *,
    paths: Sequence[str] = PATHS,
    repeats: int = 3,
    search: SearchConfig | None = None,
    restart: bool = False,
    progress: Progress | bool | None = None,
    cost: Cost | None = None,
    target: dict | None = None,
) -> list[dict]:
    """Evaluate `space` for each of `paths` into the folder `out` laid out as `store`;
    return the points evaluated, every path's, in order (module docstring).

    A point is a dict: path, settings (knob → value), and either `skipped` (why the
    renderer refused the setting) or time_s (the median of `repeats` timed renders, or
    `cost(setting)`), times, wall_s (the seconds its measurement took: warm-up and timed
    renders), rmse, max_abs, rel_rmse (RMSE over the reference's peak), tau_rmse and
    tau_max (per-point τ = exp(−κΩ) against the reference's; None without shadows or
    against a target). `search=None` evaluates every setting of the space; a
    `SearchConfig` (a `KnobSpace` only) the Pareto search's. `target`: a
    `target_reference`, every point's reference instead of each path's own (none is
    rendered). Arguments are checked by the caller (`check_run`)."""
    if search is not None and not isinstance(space, KnobSpace):
        raise TypeError("the Pareto search steps through a KnobSpace; pass search=None")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    config = {
        "scene": scene.name,
        "scene_digest": scene_digest(scene),
        "repeats": repeats,
        "timing": "measured" if cost is None else "cost model",
        "reference": reference_config(scene, space.knobs) if target is None else {"target": target["digest"]},
        store.space: space.to_json(),
        "search": None if search is None else dataclasses.asdict(search),
        "paths": list(paths),
        "size": [scene.camera.width, scene.camera.height],
    }
    store.check_config(out, config, restart)
    stored = store.load(out)
    store.rewrite(out, stored)
    with progress_of(progress, store.title) as report:
        run = _Run(
            scene=scene,
            out=out,
            space=space,
            store=store,
            repeats=repeats,
            cost=cost,
            target=target,
            report=report,
        )
        if search is None or not isinstance(space, KnobSpace):
            return _every_setting(run, paths, stored)
        return _pareto(run, space, paths, stored, search)


def _every_setting(run: _Run, paths: Sequence[str], stored: list[dict]) -> list[dict]:
    """Every setting of the space for each path, in order. `report(done, total, message)`
    after each new point, `total` all the run's points and `done` counting those a resumed
    run found finished: its first call, "resuming: N of M points already done", has
    done = N; each path's reference is reported too, with `done` unchanged."""
    planned = [(path, setting) for path in paths for setting in run.space.grid()]
    total = len(planned)
    done = [0]
    evaluators = {path: _Evaluator(run, path, stored, lambda: (done[0], total)) for path in paths}
    done[0] = sum(setting_key(s) in evaluators[path].stored for path, s in planned)
    if done[0]:
        run.report(done[0], total, f"resuming: {done[0]} of {total} points already done")
    points = []
    for path, setting in planned:
        evaluate = evaluators[path]
        points.append(evaluate(setting))
        if not evaluate.replayed:
            done[0] += 1
            skipped = " (skipped)" if "skipped" in points[-1] else ""
            run.report(done[0], total, f"{path} {run.space.label(setting)}{skipped}")
    return points


def _pareto(
    run: _Run, space: KnobSpace, paths: Sequence[str], stored: list[dict], search: SearchConfig
) -> list[dict]:
    """The Pareto search's points for each path in turn; `report(done, total, message)`
    after each new point, counted per path (the total is the budget or the space's size)."""
    points: list[dict] = []
    for path in paths:
        calls = [0]

        def position(calls=calls) -> tuple[int, int]:
            return calls[0] - 1, calls[0]  # the points before this one; the reference is not one

        evaluate = _Evaluator(run, path, stored, position)
        if evaluate.stored:
            n = len(evaluate.stored)
            run.report(0, n, f"{path}: resuming, {n} points already measured")

        def counted(setting: dict, evaluate=evaluate, calls=calls) -> dict:
            calls[0] += 1
            return evaluate(setting)

        def path_report(done: int, total: int, message: str = "", evaluate=evaluate) -> None:
            if not evaluate.replayed:  # a resumed search replays its points in a moment
                run.report(done, total, f"{evaluate.path} {message}")

        points += pareto_search(space, counted, search, path_report)
    return points


def run_sweep(
    scene: Scene,
    out,
    *,
    knobs: Mapping[str, Sequence] | None = None,
    paths: Sequence[str] = PATHS,
    repeats: int = 3,
    restart: bool = False,
    progress: Progress | bool | None = None,
    target=None,
    cost: Cost | None = None,
) -> list[dict]:
    """The one-knob sweep: every value of every knob of `knobs` (name → values; default
    `KNOBS`) for `paths`, one knob changed at a time from the scene's settings
    (`one_knob_space`, which drops the knobs that change nothing in `scene`); the points
    in order (`run_search`), each with its `knob` and `value` besides its settings.

    `target`: an `[H, W, 3|4]` image (e.g. `reference_image`'s physically based one) that
    every point of both paths is measured against instead of each path's converged
    reference: the error then includes the model's own (docs/results.md). `progress`:
    `run_search`'s calls, or True for `reporter("sweep")`'s line or bar, False for none."""
    knobs = dict(KNOBS if knobs is None else knobs)
    repeats = check_run(knobs, paths, repeats)
    given = None if target is None else target_reference(scene, target)
    space = one_knob_space(scene, knobs)
    return run_search(
        scene,
        out,
        space,
        SWEEP_STORE,
        paths=paths,
        repeats=repeats,
        restart=restart,
        progress=progress,
        cost=cost,
        target=given,
    )


def run_joint(
    scene: Scene,
    out,
    *,
    search: SearchConfig | None = SearchConfig(),
    knobs: Mapping[str, Sequence] | None = None,
    paths: Sequence[str] = PATHS,
    repeats: int = 3,
    restart: bool = False,
    progress: Progress | None = None,
    cost: Cost | None = None,
) -> list[dict]:
    """The joint search: the combinations of `knobs` (name → values, cheapest first;
    default `JOINT_KNOBS`; `knob_space`) for each of `paths`, by the Pareto search of
    `search`, or every combination with `search=None` (to check the search on a small
    space); the points in order (`run_search`). `cost` (tests): the seconds charged to a
    setting, instead of timed renders (only the warm-up render, for the error, is made)."""
    knobs = dict(JOINT_KNOBS if knobs is None else knobs)
    repeats = check_run(knobs, paths, repeats, empty_values=False)
    space = knob_space(scene, knobs)
    return run_search(
        scene,
        out,
        space,
        JOINT_STORE,
        paths=paths,
        repeats=repeats,
        search=search,
        restart=restart,
        progress=progress,
        cost=cost,
    )
