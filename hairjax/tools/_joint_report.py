"""The joint search's report (docs/results.md, "Joint search"): pareto.csv (the front, one
row per point and path), joint.csv (every point evaluated), the front plotted, and a
markdown summary with the cheapest combination reaching 1 %, 0.5 % and 0.1 % relative
RMSE, or the knobs that keep a target out of reach.

Everything here reads the points `run_joint` stored and its config; nothing renders.
"""

from __future__ import annotations

from pathlib import Path

from .._io._files import atomic_path, write_csv, write_text
from ._knob_space import KnobSpace, setting_key
from ._pareto import SearchConfig, pareto_front

__all__ = ["JOINT_THRESHOLDS", "write_joint_report", "joint_markdown", "joint_plot", "floors", "front_rows"]

JOINT_THRESHOLDS = (1e-2, 5e-3, 1e-3)  # relative RMSE: 1 %, 0.5 %, 0.1 % of the reference's peak
_MEASURES = ("time_s", "rel_rmse", "rmse", "max_abs")


def _space(config: dict) -> KnobSpace:
    return KnobSpace.from_json(config["space"])


def _of(points: list[dict], path: str) -> list[dict]:
    return [p for p in points if p["path"] == path]


def _paths(points: list[dict], config: dict) -> list[str]:
    return [p for p in config["paths"] if _of(points, p)]


def front_rows(points: list[dict], config: dict) -> list[dict]:
    """The front of each path, fastest first: path, every knob (None where the point's
    shadow method has no such knob), then its measures."""
    rows = []
    for path in _paths(points, config):
        for p in pareto_front(_of(points, path)):
            rows.append({"path": path, **{k: p["settings"].get(k) for k in _space(config).knobs}, **p})
    return rows


def cheapest(points: list[dict], threshold: float, path: str) -> dict | None:
    """The fastest measured point of `path` whose relative RMSE is at most `threshold`."""
    ok = [p for p in pareto_front(_of(points, path)) if p["rel_rmse"] <= threshold]
    return ok[0] if ok else None


def floors(points: list[dict], config: dict, path: str) -> list[str]:
    """Why the best point of `path` goes no lower: each knob at its largest value, each
    whose step up was tried and did not reduce the error (or was refused), and, if the
    budget ran out before the best point's steps were tried, that."""
    space = _space(config)
    measured = {setting_key(p["settings"]): p for p in _of(points, path)}
    front = pareto_front(measured.values())
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
        elif setting_key(step) not in measured:
            untried = True
        elif "skipped" in measured[setting_key(step)]:
            reasons.append(f"{knob}: the step up to {step[knob]} was refused")
        elif measured[setting_key(step)]["rel_rmse"] >= best["rel_rmse"]:
            reasons.append(f"{knob}: a step up (to {step[knob]}) did not reduce the error")
    switches = [setting_key(s) for s in space.switches(here)]
    if any(k not in measured for k in switches):
        untried = True
    elif switches and all(
        "skipped" in measured[k] or measured[k]["rel_rmse"] >= best["rel_rmse"] for k in switches
    ):
        reasons.append("no other shadow method reduced the error")
    search = SearchConfig(**config["search"]) if config.get("search") else None
    if untried and search is not None and search.spent(list(measured.values())):
        budget = _budget_text(search)
        reasons.append(f"the budget ({budget}) ran out before the best point's steps were tried")
    return reasons


def _budget_text(search: SearchConfig) -> str:
    parts = [] if search.budget is None else [f"{search.budget} points"]
    parts += [] if search.budget_s is None else [f"{search.budget_s:.0f} s of measuring"]
    return " and ".join(parts) + (" per path" if parts else "")


def _fmt(x) -> str:
    if x is None:
        return "–"
    return x if isinstance(x, str) else f"{x:.3g}"


def _settings_text(settings: dict) -> str:
    return ", ".join(f"{k} {v}" for k, v in settings.items())


def joint_markdown(points: list[dict], config: dict) -> str:
    """Markdown: how the search ran, the cheapest combination per threshold, the fronts."""
    space = _space(config)
    ref = config["reference"]
    paths = _paths(points, config)
    search = config.get("search")
    counts = ", ".join(f"{path} {len(_of(points, path))}" for path in paths)
    walls = {path: sum(p.get("wall_s", 0.0) for p in _of(points, path)) for path in paths}
    spent = ", ".join(f"{path} {walls[path]:.0f} s" for path in paths)
    if search is None:
        how = f"every combination ({space.size()} per path)"
    else:
        searched = SearchConfig(**search)
        budget = "" if not _budget_text(searched) else f", budget {_budget_text(searched)}"
        how = (
            f"{counts} of the {space.size()} combinations per path (search stopping at "
            f"{searched.stop_at:.2%}{budget})"
        )
    timing = (
        "times from a cost model"
        if config.get("timing") == "cost model"
        else (f"times are medians of {config['repeats']} renders after a warm-up")
    )
    lines = [
        f"# Joint search of `{config['scene']}` ({config['size'][0]}×{config['size'][1]})",
        "",
        f"Reference per path: shadows {ref['shadows']}, ordering {ref['ordering']}, supersampling "
        f"{ref['supersampling']}×{ref['supersampling']}. All knobs change together; evaluated: "
        f"{how}; measuring them took {spent}. Relative RMSE = RMSE / the reference's peak value; "
        f"{timing}.",
        "",
        "## Cheapest combination reaching each error",
        "",
        "| relative RMSE | path | time (s) | reached | settings |",
        "|---|---|---|---|---|",
    ]
    for t in JOINT_THRESHOLDS:
        for path in paths:
            c = cheapest(points, t, path)
            if c is None:
                why = "; ".join(floors(points, config, path))
                lines.append(f"| {t:.1%} | {path} | – | not reached | {why} |")
            else:
                lines.append(
                    f"| {t:.1%} | {path} | {c['time_s']:.3g} | {c['rel_rmse']:.3%} | "
                    f"{_settings_text(c['settings'])} |"
                )
    lines.append("")
    knobs = list(space.knobs)
    columns = ["#", "path", *knobs, "time_s", "rel_rmse"]
    lines += ["## The fronts", "", "| " + " | ".join(columns) + " |", "|---" * len(columns) + "|"]
    rows = front_rows(points, config)
    for i, r in enumerate(rows):
        cells = [
            str(i + 1),
            r["path"],
            *[_fmt(r[k]) for k in knobs],
            _fmt(r["time_s"]),
            f"{r['rel_rmse']:.3%}",
        ]
        lines.append("| " + " | ".join(cells) + " |")
    skipped = [p for p in points if "skipped" in p]
    if skipped:
        lines += ["", "## Settings a renderer refused", ""]
        lines += [f"- {p['path']}, {_settings_text(p['settings'])}: {p['skipped']}" for p in skipped]
    return "\n".join(lines) + "\n"


def joint_plot(points: list[dict], config: dict, path) -> Path:
    """Relative RMSE against time (log-log): every evaluated point, each path's front
    joined, the front points numbered as in the summary's table, as PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 5.5), dpi=120)
    styles = {"jax": ("-", "C0"), "gl": ("--", "C1")}
    errors = [p["rel_rmse"] for p in points if "skipped" not in p and p["rel_rmse"] > 0]
    # A point equal to its reference (RMSE 0) is drawn at this floor on the log axis, and
    # its number marked "= 0".
    floor = 0.3 * min(errors, default=1e-6)
    number = 0
    for name in _paths(points, config):
        line, color = styles.get(name, (":", "C2"))
        measured = [p for p in _of(points, name) if "skipped" not in p]
        ax.scatter(
            [p["time_s"] for p in measured],
            [max(p["rel_rmse"], floor) for p in measured],
            s=6,
            color=color,
            alpha=0.3,
            label=f"{name}: evaluated ({len(measured)})",
        )
        front = pareto_front(measured)
        x, y = [p["time_s"] for p in front], [max(p["rel_rmse"], floor) for p in front]
        # A step: the least error reached by the time on the axis.
        ax.plot(
            x,
            y,
            line,
            marker="o",
            ms=3,
            color=color,
            drawstyle="steps-post",
            label=f"{name}: front ({len(front)})",
        )
        for p, xi, yi in zip(front, x, y):
            number += 1
            text = f"{number} = 0" if p["rel_rmse"] == 0 else str(number)
            ax.annotate(text, (xi, yi), fontsize=6, xytext=(2, 2), textcoords="offset points", color=color)
    for t in JOINT_THRESHOLDS:
        ax.axhline(t, color="grey", lw=0.6, ls=":")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("median render time (s)")
    ax.set_ylabel("RMSE / reference peak")
    ax.set_title(f"Joint search, error against run time: {config['scene']}")
    ax.legend(fontsize=7)
    fig.tight_layout()
    with atomic_path(path, ".png") as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)
    return Path(path)


def write_joint_report(out, points: list[dict], config: dict) -> dict[str, Path]:
    """Write pareto.csv, joint.csv, joint_pareto.png and joint.md into `out`; return their paths."""
    out = Path(out)
    knobs = list(_space(config).knobs)
    files = {
        "pareto": out / "pareto.csv",
        "csv": out / "joint.csv",
        "plot": out / "joint_pareto.png",
        "summary": out / "joint.md",
    }
    write_csv(files["pareto"], ["path", *knobs, *_MEASURES], front_rows(points, config))
    every = [{"path": p["path"], **p["settings"], **p} for p in points if "skipped" not in p]
    write_csv(files["csv"], ["path", *knobs, *_MEASURES, "tau_rmse", "tau_max"], every)
    write_text(files["summary"], joint_markdown(points, config))
    joint_plot(points, config, files["plot"])
    return files
