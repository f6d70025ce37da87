"""The settings search's plot (docs/results.md §1 and §7): relative RMSE against run time,
log-log, for either space; and what the report (`_report.py`) shares with it: the errors
it asks the cheapest settings for, and the selections of points."""

from __future__ import annotations

import json
from pathlib import Path

from .._io._files import atomic_path
from ._pareto import pareto_front
from ._store import store_of

__all__ = ["THRESHOLDS", "pareto_plot", "measured", "of_path", "paths_of"]

# Relative RMSE (1 %, 0.5 %, 0.1 % of the reference's peak): the report's cheapest settings
# reaching each, marked across the plot.
THRESHOLDS = (1e-2, 5e-3, 1e-3)


def measured(points: list[dict]) -> list[dict]:
    """The points a renderer did not refuse."""
    return [p for p in points if "skipped" not in p]


def of_path(points: list[dict], path: str) -> list[dict]:
    return [p for p in points if p["path"] == path]


def paths_of(points: list[dict], config: dict) -> list[str]:
    """The config's paths that have points, in its order."""
    return [p for p in config["paths"] if of_path(points, p)]


def _knob_curves(ax, points: list[dict], config: dict, line: str, floor: float, colors: dict) -> None:
    """A one-knob sweep's curves: each knob's points joined in the order swept, each
    labelled with its value, a colour per knob."""
    for knob, values in config["knobs"].items():
        order = [json.dumps(v) for v in values]
        pts = sorted(
            (p for p in points if p["knob"] == knob and json.dumps(p["value"]) in order),
            key=lambda p: order.index(json.dumps(p["value"])),
        )
        if not pts:
            continue
        x, y = [p["time_s"] for p in pts], [max(p["rel_rmse"], floor) for p in pts]
        ax.plot(x, y, line, marker="o", ms=3, lw=1, color=colors[knob], label=f"{pts[0]['path']}: {knob}")
        for p, xi, yi in zip(pts, x, y):
            ax.annotate(
                str(p["value"]),
                (xi, yi),
                fontsize=6,
                xytext=(2, 2),
                textcoords="offset points",
                color=colors[knob],
            )


def pareto_plot(points: list[dict], config: dict, path) -> Path:
    """Relative RMSE against run time (log-log), as PNG: per renderer, every measured point
    and its front (a step: the least error reached by the time on the axis); a one-knob
    sweep's knobs each as a curve of its values, a joint search's front points numbered as
    its summary's table numbers them."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    store = store_of(config)
    fig, ax = plt.subplots(figsize=(8, 5.5), dpi=120)
    knob_colors = dict(zip(config.get("knobs", ()), plt.rcParams["axes.prop_cycle"].by_key()["color"]))
    errors = [p["rel_rmse"] for p in measured(points) if p["rel_rmse"] > 0]
    # A point equal to its reference (RMSE 0) is drawn at this floor on the log axis, and
    # a numbered one marked "= 0".
    floor = 0.3 * min(errors, default=1e-6)
    number = 0
    for i, name in enumerate(paths_of(points, config)):
        line = {"jax": "-", "gl": "--"}.get(name, ":")
        color = "0.35" if store.one_knob else f"C{i}"
        mine = measured(of_path(points, name))
        y_of = [max(p["rel_rmse"], floor) for p in mine]
        ax.scatter([p["time_s"] for p in mine], y_of, s=6, color=color, alpha=0.3)
        front = pareto_front(mine)
        x, y = [p["time_s"] for p in front], [max(p["rel_rmse"], floor) for p in front]
        ax.plot(
            x,
            y,
            line,
            marker="o",
            ms=3,
            color=color,
            drawstyle="steps-post",
            label=f"{name}: front ({len(front)} of {len(mine)})",
        )
        if store.one_knob:
            _knob_curves(ax, mine, config, line, floor, knob_colors)
            continue
        for p, xi, yi in zip(front, x, y):
            number += 1
            text = f"{number} = 0" if p["rel_rmse"] == 0 else str(number)
            ax.annotate(text, (xi, yi), fontsize=6, xytext=(2, 2), textcoords="offset points", color=color)
    for t in THRESHOLDS:
        ax.axhline(t, color="grey", lw=0.6, ls=":")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("median render time (s)")
    ax.set_ylabel("RMSE / reference peak")
    ax.set_title(f"{store.title.capitalize()}, error against run time: {config['scene']}")
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    with atomic_path(path, ".png") as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)
    return Path(path)
