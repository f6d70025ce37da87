"""The settings search's report (docs/results.md §1 and §7): CSV tables, the plot of error
against run time (`_plot.py`) and a markdown summary, for either space.

Everything here reads the points `run_search` stored and its config; nothing renders.
The summary holds, per path, the cheapest setting reaching each relative RMSE of
`THRESHOLDS` (against a given target image, first the cheapest within 10 % of the best
error reached), the settings a renderer refused, and a table. What the space adds:
- one knob at a time (`run_sweep`): per threshold, the cheapest value of each knob as
  well; the table lists every point. Files: sweep.csv (every point), pareto.png,
  summary.md.
- the joint search (`run_joint`): where a threshold is not reached, the knobs that keep it
  out of reach (`floors`); the table lists each path's front. Files: pareto.csv (the
  fronts), joint.csv (every point), joint_pareto.png, joint.md.
"""

from __future__ import annotations

import json
from pathlib import Path

from .._io._files import write_csv, write_text
from ._knob_space import KnobSpace, setting_key
from ._pareto import SearchConfig, pareto_front
from ._plot import THRESHOLDS, measured, of_path, pareto_plot, paths_of
from ._store import Store, store_of

__all__ = [
    "THRESHOLDS",
    "write_report",
    "summary_markdown",
    "cheapest",
    "floors",
    "front_rows",
    "pareto_plot",
]

# Against a given target: the settings whose error is within 10 % of the best point's.
NEAR_BEST = 1.1
# The every-point CSV of a one-knob sweep (sweep.csv); a joint search's holds each knob.
_SWEEP_COLUMNS = ("path", "knob", "value", "time_s", "rmse", "rel_rmse", "max_abs", "tau_rmse", "tau_max")
_MEASURES = ("time_s", "rel_rmse", "rmse", "max_abs")


def cheapest(points: list[dict], threshold: float, path: str, knob: str | None = None) -> dict | None:
    """The fastest measured point of `path` (and of one-knob points, `knob`) whose relative
    RMSE is at most `threshold`; of two as fast, the lower error (a point of the front)."""
    ok = [
        p
        for p in measured(of_path(points, path))
        if (knob is None or p["knob"] == knob) and p["rel_rmse"] <= threshold
    ]
    return min(ok, key=lambda p: (p["time_s"], p["rel_rmse"]), default=None)


def _fmt(x) -> str:
    if x is None:
        return "–"
    return x if isinstance(x, str) else f"{x:.3g}"


def _setting_text(store: Store, point: dict) -> str:
    if store.one_knob:
        return f"{point['knob']} = {point['value']}"
    return ", ".join(f"{k} {v}" for k, v in point["settings"].items())


def _bounds(points: list[dict], config: dict, paths: list[str]) -> list[tuple[str, str, dict]]:
    """(label, title, path → relative RMSE) of each error the summary asks the cheapest
    setting for: `THRESHOLDS`, after, against a given target, 10 % above the best error."""
    bounds = [(f"{t:.1%}", f"reaching {t:.1%} relative RMSE", {p: t for p in paths}) for t in THRESHOLDS]
    if "target" in config["reference"]:
        best = {p: min((q["rel_rmse"] for q in measured(of_path(points, p))), default=0.0) for p in paths}
        near = {p: NEAR_BEST * best[p] for p in paths}
        bounds.insert(0, (f"≤ {NEAR_BEST:g} × best", f"within {NEAR_BEST - 1:.0%} of the best error", near))
    return bounds


def _budget_text(search: SearchConfig) -> str:
    parts = [] if search.budget is None else [f"{search.budget} points"]
    parts += [] if search.budget_s is None else [f"{search.budget_s:.0f} s of measuring"]
    return " and ".join(parts) + (" per path" if parts else "")


def _intro(points: list[dict], config: dict, store: Store, paths: list[str]) -> str:
    """The summary's first paragraph: the reference, how the space was walked, the units."""
    ref = config["reference"]
    if "target" in ref:  # a given image (e.g. the physically based reference)
        against = (
            f"Every point is measured against one given target image (digest {ref['target']}), "
            "so each error includes the model's own: a curve levels off at it."
        )
    else:
        s = ref["supersampling"]
        against = (
            f"Reference per path: shadows {ref['shadows']}, ordering {ref['ordering']}, "
            f"supersampling {s}×{s}."
        )
    if store.one_knob:
        walked = (
            "One knob changes at a time, the others keep the scene's settings, so each curve "
            "levels off at the error of the settings it does not change."
        )
    else:
        size = store.space_of(config).size()
        spent = ", ".join(f"{p} {sum(q.get('wall_s', 0.0) for q in of_path(points, p)):.0f} s" for p in paths)
        how = f"every combination ({size} per path)"
        if config.get("search") is not None:
            search = SearchConfig(**config["search"])
            budget = "" if not _budget_text(search) else f", budget {_budget_text(search)}"
            counts = ", ".join(f"{p} {len(of_path(points, p))}" for p in paths)
            stop = f"search stopping at {search.stop_at:.2%}{budget}"
            how = f"{counts} of the {size} combinations per path ({stop})"
        walked = f"All knobs change together; evaluated: {how}; measuring them took {spent}."
    timing = (
        "times from a cost model"
        if config.get("timing") == "cost model"
        else f"times are medians of {config['repeats']} renders after a warm-up"
    )
    return f"{against} {walked} Relative RMSE = RMSE / the reference's peak value; {timing}."


def _knob_tables(points: list[dict], config: dict, paths: list[str]) -> list[str]:
    """Per error bound, the cheapest setting of each path, overall and of each knob."""
    lines = []
    knobs = list(config["knobs"])
    for _, title, bound in _bounds(points, config, paths):
        lines += [f"## Cheapest settings {title}", ""]
        lines += ["| path | overall | " + " | ".join(knobs) + " |", "|---|---|" + "---|" * len(knobs)]
        for path in paths:
            cells = []
            for knob in (None, *knobs):
                c = cheapest(points, bound[path], path, knob)
                if c is None:
                    cells.append("not reached")
                else:
                    cells.append(
                        f"{c['knob'] + ' = ' if knob is None else ''}{c['value']} ({c['time_s']:.3g} s)"
                    )
            lines.append(f"| {path} | " + " | ".join(cells) + " |")
        lines.append("")
    return lines


def _combination_table(points: list[dict], config: dict, paths: list[str]) -> list[str]:
    """Per error bound and path, the cheapest combination, or why none reaches it."""
    lines = [
        "## Cheapest combination reaching each error",
        "",
        "| relative RMSE | path | time (s) | reached | settings |",
        "|---|---|---|---|---|",
    ]
    for label, _, bound in _bounds(points, config, paths):
        for path in paths:
            c = cheapest(points, bound[path], path)
            if c is None:
                why = "; ".join(floors(points, config, path))
                lines.append(f"| {label} | {path} | – | not reached | {why} |")
            else:
                text = _setting_text(store_of(config), c)
                lines.append(f"| {label} | {path} | {c['time_s']:.3g} | {c['rel_rmse']:.3%} | {text} |")
    return [*lines, ""]


def floors(points: list[dict], config: dict, path: str) -> list[str]:
    """Why the best point of a joint search's `path` goes no lower: each knob at its
    largest value, each whose step up was tried and did not reduce the error (or was
    refused), and, if the budget ran out before the best point's steps were tried, that."""
    space = store_of(config).space_of(config)
    assert isinstance(space, KnobSpace), "floors are the joint search's"
    tried = {setting_key(p["settings"]): p for p in of_path(points, path)}
    front = pareto_front(tried.values())
    if not front:
        return ["no point was measured"]
    best = front[-1]
    here = best["settings"]
    reasons = []
    untried = False
    for knob in space.ordered(here):
        step = space.up(here, knob)
        if step is None:
            reasons.append(f"{knob} at its largest value ({here[knob]})")
        elif setting_key(step) not in tried:
            untried = True
        elif "skipped" in tried[setting_key(step)]:
            reasons.append(f"{knob}: the step up to {step[knob]} was refused")
        elif tried[setting_key(step)]["rel_rmse"] >= best["rel_rmse"]:
            reasons.append(f"{knob}: a step up (to {step[knob]}) did not reduce the error")
    switches = [setting_key(s) for s in space.switches(here)]
    if any(k not in tried for k in switches):
        untried = True
    elif switches and all(
        "skipped" in tried[k] or tried[k]["rel_rmse"] >= best["rel_rmse"] for k in switches
    ):
        reasons.append("no other shadow method reduced the error")
    search = SearchConfig(**config["search"]) if config.get("search") else None
    if untried and search is not None and search.spent(list(tried.values())):
        reasons.append(
            f"the budget ({_budget_text(search)}) ran out before the best point's steps were tried"
        )
    return reasons


def _sorted(points: list[dict], config: dict) -> list[dict]:
    """One-knob points in the order swept: path, knob, value as the config lists them."""
    order = {k: [json.dumps(v) for v in vs] for k, vs in config["knobs"].items()}

    def key(p):
        values = order.get(p["knob"], [])
        v = json.dumps(p["value"])
        return (
            config["paths"].index(p["path"]) if p["path"] in config["paths"] else 99,
            list(config["knobs"]).index(p["knob"]) if p["knob"] in config["knobs"] else 99,
            values.index(v) if v in values else 99,
        )

    return sorted(points, key=key)


def front_rows(points: list[dict], config: dict) -> list[dict]:
    """The front of each path of a joint search, fastest first: path, every knob (None
    where the point's shadow method has no such knob), then its measures."""
    knobs = store_of(config).space_of(config).knobs
    rows = []
    for path in paths_of(points, config):
        for p in pareto_front(of_path(points, path)):
            rows.append({"path": path, **{k: p["settings"].get(k) for k in knobs}, **p})
    return rows


def _table(points: list[dict], config: dict) -> list[str]:
    """The summary's last section: every point of a sweep, the fronts of a joint search
    (numbered as the plot numbers them)."""
    if store_of(config).one_knob:
        lines = [
            "## All points",
            "",
            "| " + " | ".join(_SWEEP_COLUMNS) + " |",
            "|---" * len(_SWEEP_COLUMNS) + "|",
        ]
        for p in _sorted(measured(points), config):
            cells = [_fmt(p.get(c)) if c != "value" else str(p["value"]) for c in _SWEEP_COLUMNS]
            lines.append("| " + " | ".join(cells) + " |")
        return lines
    knobs = list(store_of(config).space_of(config).knobs)
    columns = ["#", "path", *knobs, "time_s", "rel_rmse"]
    lines = ["## The fronts", "", "| " + " | ".join(columns) + " |", "|---" * len(columns) + "|"]
    for i, r in enumerate(front_rows(points, config)):
        cells = [
            str(i + 1),
            r["path"],
            *[_fmt(r[k]) for k in knobs],
            _fmt(r["time_s"]),
            f"{r['rel_rmse']:.3%}",
        ]
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def summary_markdown(points: list[dict], config: dict) -> str:
    """Markdown: how the search ran, the cheapest settings per error, the settings refused,
    the table (module docstring)."""
    store = store_of(config)
    paths = paths_of(points, config)
    width, height = config["size"]
    lines = [
        f"# {store.title.capitalize()} of `{config['scene']}` ({width}×{height})",
        "",
        _intro(points, config, store, paths),
        "",
    ]
    if store.one_knob:
        lines += _knob_tables(points, config, paths)
    else:
        lines += _combination_table(points, config, paths)
    skipped = [p for p in points if "skipped" in p]
    if skipped:
        lines += ["## Settings a renderer refused", ""]
        lines += [f"- {p['path']}, {_setting_text(store, p)}: {p['skipped']}" for p in skipped]
        lines.append("")
    return "\n".join(lines + _table(points, config)) + "\n"


def write_report(out, points: list[dict], config: dict) -> dict[str, Path]:
    """Write the report's files into `out` (module docstring); return their paths, by
    kind: `csv` (every point), `plot`, `summary`, and a joint search's `pareto` (the fronts)."""
    out = Path(out)
    if store_of(config).one_knob:
        files = {"csv": out / "sweep.csv", "plot": out / "pareto.png", "summary": out / "summary.md"}
        write_csv(files["csv"], _SWEEP_COLUMNS, _sorted(measured(points), config))
    else:
        files = {
            "pareto": out / "pareto.csv",
            "csv": out / "joint.csv",
            "plot": out / "joint_pareto.png",
            "summary": out / "joint.md",
        }
        knobs = list(store_of(config).space_of(config).knobs)
        write_csv(files["pareto"], ["path", *knobs, *_MEASURES], front_rows(points, config))
        every = [{"path": p["path"], **p["settings"], **p} for p in measured(points)]
        write_csv(files["csv"], ["path", *knobs, *_MEASURES, "tau_rmse", "tau_max"], every)
    write_text(files["summary"], summary_markdown(points, config))
    pareto_plot(points, config, files["plot"])
    return files
