"""The sweep's report: a CSV table, a Pareto plot and a markdown summary (docs/results.md §1).

Everything here reads the points `run_sweep` stored; nothing renders.
"""

from __future__ import annotations

import json
from pathlib import Path

from .._io._files import atomic_path, write_csv, write_text

__all__ = ["write_report", "summary_markdown", "cheapest", "pareto_plot", "THRESHOLDS"]

THRESHOLDS = (1e-2, 1e-3)  # relative RMSE: 1 % and 0.1 % of the reference's peak
# Against a given target: the settings whose error is within 10 % of the best point's.
NEAR_BEST = 1.1
_COLUMNS = ("path", "knob", "value", "time_s", "rmse", "rel_rmse", "max_abs", "tau_rmse", "tau_max")


def cheapest(points: list[dict], threshold: float, path: str, knob: str | None = None) -> dict | None:
    """The fastest point of `path` (and `knob`) whose relative RMSE is at most `threshold`."""
    ok = [
        p
        for p in _measured(points)
        if p["path"] == path and (knob is None or p["knob"] == knob) and p["rel_rmse"] <= threshold
    ]
    return min(ok, key=lambda p: p["time_s"], default=None)


def _measured(points: list[dict]) -> list[dict]:
    return [p for p in points if "skipped" not in p]


def _fmt(x) -> str:
    if x is None:
        return "–"
    if isinstance(x, str):
        return x
    return f"{x:.3g}"


def summary_markdown(points: list[dict], config: dict) -> str:
    """Markdown: the settings, the cheapest settings reaching each threshold, the table."""
    ref = config["reference"]
    paths = [p for p in config["paths"] if any(q["path"] == p for q in points)]
    if "target" in ref:  # a given image (e.g. the physically based reference)
        against = (
            f"Every point is measured against one given target image (digest {ref['target']}), "
            "so each error includes the model's own: a curve levels off at it."
        )
    else:
        against = (
            f"Reference per path: shadows {ref['shadows']}, ordering {ref['ordering']}, "
            f"supersampling {ref['supersampling']}×{ref['supersampling']}."
        )
    lines = [
        f"# Sweep of `{config['scene']}` ({config['size'][0]}×{config['size'][1]})",
        "",
        f"{against} One knob changes at a "
        "time, the others keep the scene's settings, so each curve levels off at the error "
        "of the settings it does not change. Relative RMSE = RMSE / the reference's peak "
        f"value; times are medians of {config['repeats']} renders after a warm-up.",
        "",
    ]
    thresholds: list[tuple[str, dict]] = [
        (f"reaching {t:.1%} relative RMSE", {p: t for p in paths}) for t in THRESHOLDS
    ]
    if "target" in ref:
        best = {
            p: min((q["rel_rmse"] for q in _measured(points) if q["path"] == p), default=0.0) for p in paths
        }
        thresholds.insert(
            0, (f"within {NEAR_BEST - 1:.0%} of the best error", {p: NEAR_BEST * best[p] for p in paths})
        )
    for title, bound in thresholds:
        lines.append(f"## Cheapest settings {title}")
        lines.append("")
        lines.append("| path | overall | " + " | ".join(config["knobs"]) + " |")
        lines.append("|---|---|" + "---|" * len(config["knobs"]))
        for path in paths:
            cells = []
            for knob in (None, *config["knobs"]):
                c = cheapest(points, bound[path], path, knob)
                if c is None:
                    cells.append("not reached")
                elif knob is None:
                    cells.append(f"{c['knob']} = {c['value']} ({c['time_s']:.3g} s)")
                else:
                    cells.append(f"{c['value']} ({c['time_s']:.3g} s)")
            lines.append(f"| {path} | " + " | ".join(cells) + " |")
        lines.append("")
    skipped = [p for p in points if "skipped" in p]
    if skipped:
        lines += ["## Settings a renderer refused", ""]
        lines += [f"- {p['path']}, {p['knob']} = {p['value']}: {p['skipped']}" for p in skipped]
        lines.append("")
    lines += ["## All points", "", "| " + " | ".join(_COLUMNS) + " |", "|---" * len(_COLUMNS) + "|"]
    for p in _sorted(_measured(points), config):
        lines.append(
            "| " + " | ".join(_fmt(p.get(c)) if c != "value" else str(p["value"]) for c in _COLUMNS) + " |"
        )
    return "\n".join(lines) + "\n"


def _sorted(points: list[dict], config: dict) -> list[dict]:
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


def pareto_plot(points: list[dict], config: dict, path) -> Path:
    """Relative RMSE against median time, one curve per knob and path (log-log), as PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 5.5), dpi=120)
    styles = {"jax": "-", "gl": "--"}
    colors = dict(zip(config["knobs"], plt.rcParams["axes.prop_cycle"].by_key()["color"]))
    floor = 1e-7  # a point equal to its reference (RMSE 0) is drawn at this floor on log axes
    for p_name in config["paths"]:
        for knob in config["knobs"]:
            pts = [p for p in _sorted(_measured(points), config) if p["path"] == p_name and p["knob"] == knob]
            if not pts:
                continue
            x = [p["time_s"] for p in pts]
            y = [max(p["rel_rmse"], floor) for p in pts]
            ax.plot(
                x, y, styles.get(p_name, ":"), marker="o", ms=3, color=colors[knob], label=f"{p_name}: {knob}"
            )
            for p, xi, yi in zip(pts, x, y):
                ax.annotate(
                    str(p["value"]),
                    (xi, yi),
                    fontsize=6,
                    xytext=(2, 2),
                    textcoords="offset points",
                    color=colors[knob],
                )
    for t in THRESHOLDS:
        ax.axhline(t, color="grey", lw=0.6, ls=":")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("median render time (s)")
    ax.set_ylabel("RMSE / reference peak")
    ax.set_title(f"Error against run time: {config['scene']}")
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    with atomic_path(path, ".png") as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)
    return Path(path)


def write_report(out, points: list[dict], config: dict) -> dict[str, Path]:
    """Write sweep.csv, pareto.png and summary.md into `out`; return their paths."""
    out = Path(out)
    files = {"csv": out / "sweep.csv", "plot": out / "pareto.png", "summary": out / "summary.md"}
    write_csv(files["csv"], _COLUMNS, _sorted(_measured(points), config))
    write_text(files["summary"], summary_markdown(points, config))
    pareto_plot(points, config, files["plot"])
    return files
