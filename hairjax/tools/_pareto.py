"""The joint search's algorithm (docs/results.md, "Joint search"): the Pareto front of
(time, error) over a `KnobSpace`, found without evaluating the whole grid.

Pure: the search sees a setting's time and error only through `evaluate(setting)`, a
point dict with `time_s` and `rel_rmse` (or `skipped`: a setting the renderer refused).
The run (`_search.py`) measures them; a test hands in times from a cost model, so that it
checks the algorithm exactly.

The search, in two phases, never evaluating a setting twice:

1. Greedy descent (the cheapest route to the target): from the cheapest setting, evaluate
   every step from the current setting and move to the one with the largest error
   reduction per second of added time (the added time taken as at least
   `time_tolerance` of the current time, so that a step whose time differs by noise is
   not free); stop at the error target `stop_at` or when no step reduces the error.
2. Closing the front, a Pareto local search (Paquete, Chiarandini and Stützle, "Pareto
   local optimum sets in the bi-objective traveling salesman problem", 2004): while a
   point near the front of everything evaluated has an error above the target and has
   not been expanded, expand it, the lowest error first. Near the front: no point is
   both `time_tolerance` faster and no worse in error, so that timing noise of that size
   cannot hide a point and its steps.

Expanding a setting evaluates its steps (`KnobSpace.steps`): each knob one value up, and
each other shadow method. A step that does not reduce the error is followed by the next
value of the same knob as well, since a knob's error can rise before it falls (1 → 2 → 4
opacity maps on a coarse raster).

It ends when every point near the front and above the target is expanded: a point of the
full grid's front is missed only if no chain of steps leads to it through such points.
tests/tools/test_joint.py checks against the full grid of a small space that none is
missed. The front below the target is not searched (its points cost more than the first
point reaching it). `budget` bounds the settings evaluated, `budget_s` the seconds spent
measuring them: the search stops before the first setting past either.
"""

from __future__ import annotations

import bisect
import dataclasses
import itertools
import math
from collections.abc import Callable, Iterable, Mapping, Sequence

from .._progress import Progress
from ._knob_space import KnobSpace, setting_key, setting_label

__all__ = ["SearchConfig", "pareto_front", "near_front", "pareto_search", "measuring_time"]


@dataclasses.dataclass(frozen=True)
class SearchConfig:
    """`stop_at`: the relative RMSE at which the search stops descending (the front below
    it is not searched); `budget`: the most settings evaluated per path, `budget_s`: the
    most seconds spent measuring them per path (each point's `wall_s`, or its `time_s`
    where it has none), None for no bound; `time_tolerance`: a point is expanded unless
    another is this fraction faster and no worse (0.1: the spread of repeated timings)."""

    stop_at: float = 5e-4
    budget: int | None = None
    budget_s: float | None = None
    time_tolerance: float = 0.1

    def __post_init__(self):
        if not (isinstance(self.stop_at, (int, float)) and self.stop_at >= 0):
            raise ValueError(f"stop_at must be a relative RMSE ≥ 0, got {self.stop_at!r}")
        if self.budget is not None and (not isinstance(self.budget, int) or self.budget < 1):
            raise ValueError(f"budget must be a positive integer or None, got {self.budget!r}")
        if self.budget_s is not None and not (isinstance(self.budget_s, (int, float)) and self.budget_s > 0):
            raise ValueError(f"budget_s must be a positive number of seconds or None, got {self.budget_s!r}")
        if not (isinstance(self.time_tolerance, (int, float)) and self.time_tolerance >= 0):
            raise ValueError(f"time_tolerance must be ≥ 0, got {self.time_tolerance!r}")

    def spent(self, points: Sequence[Mapping]) -> bool:
        """Whether `points` (one path's) use up the budget: no further point is evaluated."""
        if self.budget is not None and len(points) >= self.budget:
            return True
        return self.budget_s is not None and sum(measuring_time(p) for p in points) >= self.budget_s


def measuring_time(point: Mapping) -> float:
    """The seconds a point's measurement took: its `wall_s`, else its `time_s`, else 0."""
    return float(point.get("wall_s", point.get("time_s", 0.0)))


def near_front(points: Iterable[Mapping], tolerance: float = 0.0) -> list:
    """The measured points that no other dominates by more than `tolerance` in time: no
    point q with q's time × (1 + tolerance) ≤ p's, q's error ≤ p's, and q faster or
    better. With 0, the Pareto front (two points equal in both are both kept)."""
    measured = [p for p in points if "skipped" not in p]
    ranked = sorted(measured, key=lambda p: (p["time_s"], p["rel_rmse"]))
    times = [p["time_s"] for p in ranked]
    scaled = [t * (1 + tolerance) for t in times]
    lowest = list(itertools.accumulate((p["rel_rmse"] for p in ranked), min))

    def dominated(p) -> bool:
        within = bisect.bisect_right(scaled, p["time_s"])  # q's time × (1 + tol) ≤ p's
        faster = min(within, bisect.bisect_left(times, p["time_s"]))  # ... and q's < p's
        return (faster > 0 and lowest[faster - 1] <= p["rel_rmse"]) or (
            within > 0 and lowest[within - 1] < p["rel_rmse"]
        )

    return [p for p in measured if not dominated(p)]


def pareto_front(points: Iterable[Mapping]) -> list:
    """The Pareto front of (time_s, rel_rmse), fastest first."""
    return sorted(near_front(points), key=lambda p: (p["time_s"], p["rel_rmse"]))


class _BudgetSpent(Exception):
    pass


def pareto_search(
    space: KnobSpace,
    evaluate: Callable[[dict], dict],
    config: SearchConfig = SearchConfig(),
    progress: Progress | None = None,
) -> list[dict]:
    """Every point the search evaluated, in order (module docstring)."""
    points: dict[str, dict] = {}  # by setting_key, in the order evaluated
    settings: dict[str, dict] = {}
    expanded: set[str] = set()

    def ev(setting: dict) -> str:
        key = setting_key(setting)
        if key not in points:
            if config.spent(list(points.values())):
                raise _BudgetSpent
            points[key], settings[key] = evaluate(setting), setting
            if progress is not None:
                p = points[key]
                error = "skipped" if "skipped" in p else f"{p['rel_rmse']:.3%} in {p['time_s']:.3g} s"
                # The total is not known ahead: at most the grid, or the budget.
                total = min(space.size(), config.budget or space.size())
                progress(len(points), total, f"{setting_label(setting)}: {error}")
        return key

    def reduces(key: str, than: str) -> bool:
        p, q = points[key], points[than]
        return "skipped" not in p and p["rel_rmse"] < q["rel_rmse"]

    def expand(key: str) -> list[str]:
        """Evaluate the steps of a measured point; return their keys."""
        expanded.add(key)
        here = settings[key]
        steps = []
        for knob in space.ordered(here):
            step = space.up(here, knob)
            if step is not None:
                steps.append(ev(step))
                if not reduces(steps[-1], key) and (further := space.up(step, knob)) is not None:
                    steps.append(ev(further))
        return steps + [ev(s) for s in space.switches(here)]

    def above(key: str) -> bool:
        return "skipped" not in points[key] and points[key]["rel_rmse"] > config.stop_at

    try:
        current = ev(space.start())
        while above(current):  # 1. greedy descent
            here, best, best_rank = points[current], None, (-math.inf, -math.inf)
            for key in expand(current):
                if reduces(key, current):
                    p = points[key]
                    gain, added = here["rel_rmse"] - p["rel_rmse"], p["time_s"] - here["time_s"]
                    # Timing noise of `time_tolerance` makes no step free: a step within
                    # it is charged that much, so a tiny gain cannot win by noise alone.
                    added = max(added, config.time_tolerance * here["time_s"])
                    rank = (math.inf if added <= 0 else gain / added, gain)
                    if rank > best_rank:
                        best, best_rank = key, rank
            if best is None:
                break
            current = best
        while True:  # 2. closing the front
            key_of = {id(p): k for k, p in points.items()}
            near = [key_of[id(p)] for p in near_front(points.values(), config.time_tolerance)]
            todo = [k for k in near if above(k) and k not in expanded]
            if not todo:
                break
            expand(min(todo, key=lambda k: points[k]["rel_rmse"]))
    except _BudgetSpent:
        pass
    return list(points.values())
