"""The output of `hairjax bench`: the table it prints and its strict JSON (no NaN)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

from .._io._files import write_json
from ._bench_cases import (
    FULL_RENDER_TARGET_CONFIG,
    GL_PASSES,
    GL_TARGET_RATIO,
    JAX_TARGET_CONFIGS,
    JAX_TARGET_RATIO,
    PEAK_RSS_TARGET_GIB,
    STAGE_LABELS,
    TARGETS,
    config_name,
)

__all__ = ["format_table", "write_json_strict", "verdict", "verdict_line", "missed_targets", "QUICK_NOTE"]

# The targets' names in the table, by their key in `targets_met`.
TARGET_LABELS = {
    "shading_s": "shading stage",
    "gradient_over_shading": "gradient / shading",
    "full_render_s": "full render",
    "ordering_msegments_per_s": "ordering",
    "peak_rss": "peak RSS",
    "jax_over_gl": "JAX / GL full render",
    "jax_no_slower_than_gl": "JAX no slower than GL",
}
QUICK_NOTE = (
    "targets not judged: --quick runs one small configuration to check that the benchmark "
    "runs; the targets are set for the full configurations, where fixed costs (a call's "
    "dispatch, the gradient's extra pass) no longer dominate the times (BENCHMARKS.md)"
)


def missed_targets(result: dict) -> list[str]:
    """The targets `result` missed, by key, in the order they were judged."""
    return [key for key, met in result.get("targets_met", {}).items() if not met]


def verdict(result: dict, judged: bool) -> str:
    """A configuration's status: its run's failure (`MemoryError`, `error`) if it failed;
    else `ran` where the targets are not judged (--quick), `ok` where every target it has
    was met, and `MISS (k of n)` where k of its n targets were missed."""
    if result.get("status") != "ok":
        return str(result.get("status", "?"))
    if not judged:
        return "ran"
    missed, n = missed_targets(result), len(result.get("targets_met", {}))
    return f"MISS ({len(missed)} of {n})" if missed else "ok"


def verdict_line(configs: list[dict], results: list[dict], judged: bool) -> str:
    """The line under the table: the targets missed, by configuration, or all met."""
    if not judged:
        return QUICK_NOTE
    judged_results = [r for r in results if r.get("status") == "ok"]
    total = sum(len(r.get("targets_met", {})) for r in judged_results)
    missed = [
        f"{TARGET_LABELS.get(key, key)} at {config_name(c)}"
        for c, r in zip(configs, results)
        for key in missed_targets(r)
    ]
    if not missed:
        return f"targets: all {total} met"
    return f"targets: {len(missed)} of {total} missed: " + "; ".join(missed)


def _fmt_time(s) -> str:
    if s is None or not math.isfinite(s):
        return "-"
    if s < 1.0:
        return f"{s * 1e3:.1f} ms"
    return f"{s:.2f} s"


def _target_config() -> dict:
    return dict(strands=FULL_RENDER_TARGET_CONFIG[0], size=FULL_RENDER_TARGET_CONFIG[1])


def _mark(met) -> str:
    return "" if met is None else (" ok" if met else " MISS")


class _Row(NamedTuple):
    """One line of the table: its label, one cell per configuration, and the target."""

    label: str
    cells: list[str]
    target: str = ""


@dataclasses.dataclass(frozen=True)
class _Columns:
    """The table's columns: one configuration and its run's result each."""

    configs: list[dict]
    results: list[dict]

    def cells(self, fn: Callable[[dict, dict], str]) -> list[str]:
        """`fn(config, result)` in each column whose run succeeded; empty in the others."""
        return [fn(c, r) if r.get("status") == "ok" else "" for c, r in zip(self.configs, self.results)]

    def jax_cells(self, fn: Callable[[dict, dict], str]) -> list[str]:
        """`cells`, empty too where the run has no JAX figures."""
        return self.cells(lambda c, r: fn(c, r) if "stages" in r else "")

    def gl_cells(self, fn: Callable[[dict, dict], str]) -> list[str]:
        """`cells`, empty too where the GL run did not succeed."""
        return self.cells(lambda c, r: fn(c, r) if r.get("gl", {}).get("status") == "ok" else "")


def _stage(key: str) -> Callable[[dict, dict], str]:
    """A cell: the median time of the JAX stage `key` ("-" where the run has none)."""
    return lambda c, r: _fmt_time(r["stages"].get(key, {}).get("median_s"))


def _gl_pass(key: str) -> Callable[[dict, dict], str]:
    """A cell: the median time of the GL pass `key` ("-" where the run has none)."""
    return lambda c, r: _fmt_time(r["gl"]["passes"].get(key, {}).get("median_s"))


def _gl_work(fields: tuple[str, str], unit: float = 1.0) -> Callable[[dict, dict], str]:
    """A cell: two counts of a warm GL render's work (`hairjax/gl/_work.py`), in `unit`s
    ("-" for a run from before they were counted)."""

    def cell(c: dict, r: dict) -> str:
        work = r["gl"].get("work")
        if work is None or any(f not in work for f in fields):
            return "-"
        return " / ".join(
            f"{work[f] / unit:,.0f}" if unit == 1.0 else f"{work[f] / unit:,.1f}" for f in fields
        )

    return cell


def _marked(figure: Callable[[dict], str], target: str) -> Callable[[dict, dict], str]:
    """A cell: `figure(result)`, marked against `target` (a key of targets_met)."""
    return lambda c, r: figure(r) + _mark(r["targets_met"].get(target))


def format_table(configs: list[dict], results: list[dict], header: str) -> str:
    """`hairjax bench`'s table: one row per figure (the JAX stages and ordering, the GL
    passes, their ratio, peak RSS, status), one column per configuration, each figure
    marked against its target; then the runs' errors."""
    columns = _Columns(configs, results)
    have_jax = any("stages" in r for r in results)
    rows: list[_Row] = []
    if have_jax:
        rows += _stage_rows(columns) + _ordering_rows(columns)
    if any("gl" in r for r in results):
        rows += _gl_rows(columns, have_jax)
    rows.append(_peak_rss_row(results))
    rows.append(_Row("status", [r.get("verdict", r.get("status", "?")) for r in results]))
    names = [config_name(c) for c in configs]
    return "\n".join(_aligned(header, names, rows) + _error_lines(names, results))


def _stage_rows(columns: _Columns) -> list[_Row]:
    """The JAX stages: the set-up and its sub-steps, the opacity stage, the shading stage,
    its gradient and the full render."""
    substeps: list[str] = []
    for r in columns.results:
        for key in r.get("stages", {}):
            if key.startswith("geometry_setup/") and key not in substeps:
                substeps.append(key)
    return [
        _Row(STAGE_LABELS["geometry_setup"], columns.jax_cells(_stage("geometry_setup"))),
        *(_Row("  " + key.split("/", 1)[1], columns.jax_cells(_stage(key))) for key in substeps),
        _Row(STAGE_LABELS["geometry_opacity"], columns.jax_cells(_stage("geometry_opacity"))),
        _Row(
            STAGE_LABELS["shading"],
            columns.jax_cells(_marked(lambda r: _fmt_time(r["stages"]["shading"]["median_s"]), "shading_s")),
            f"<= {TARGETS['shading_s'] * 1e3:.0f} ms",
        ),
        _Row(STAGE_LABELS["gradient"], columns.jax_cells(_stage("gradient"))),
        _Row(
            "  gradient / shading",
            columns.jax_cells(
                _marked(lambda r: f"{r['gradient_over_shading']:.2f}x", "gradient_over_shading")
            ),
            f"<= {TARGETS['gradient_over_shading']:g}x",
        ),
        _Row(
            STAGE_LABELS["full_render"],
            columns.jax_cells(
                _marked(lambda r: _fmt_time(r["stages"]["full_render"]["median_s"]), "full_render_s")
            ),
            f"<= {TARGETS['full_render_s']:g} s at "
            f"{FULL_RENDER_TARGET_CONFIG[0] // 1000}k @ {FULL_RENDER_TARGET_CONFIG[1]}",
        ),
    ]


def _ordering_rows(columns: _Columns) -> list[_Row]:
    """The ordering's throughput (against kim-2003's) and the fragment counts."""
    return [
        _Row(
            "ordering (M segments/s)",
            columns.jax_cells(
                _marked(lambda r: f"{r['ordering']['msegments_per_s']:.1f}", "ordering_msegments_per_s")
            ),
            f">= {TARGETS['ordering_msegments_per_s']:g}",
        ),
        _Row(
            "  speed-up over kim-2003",
            columns.jax_cells(lambda c, r: f"{r['ordering']['speedup_over_kim_2003']:.0f}x"),
            "(0.7 M/s, P-III 700 MHz)",
        ),
        _Row("  segments ordered", columns.jax_cells(lambda c, r: f"{r['ordering']['segments']:,}")),
        _Row("camera fragments", columns.jax_cells(lambda c, r: f"{r['fragments']:,}")),
        _Row(
            "shadow-map fragments",
            columns.jax_cells(
                lambda c, r: "-" if r["shadow_fragments"] is None else f"{r['shadow_fragments']:,}"
            ),
        ),
    ]


def _gl_rows(columns: _Columns, have_jax: bool) -> list[_Row]:
    """The GL passes and full render, with JAX's figures their ratio against the targets,
    and the GL runs' status."""
    rows = [_Row(f"GL {key}", columns.gl_cells(_gl_pass(key))) for key in GL_PASSES]
    rows += [
        _Row("  draws / binds", columns.gl_cells(_gl_work(("draws", "binds")))),
        _Row("  dispatches / barriers", columns.gl_cells(_gl_work(("dispatches", "barriers")))),
        _Row("  MB uploaded / read", columns.gl_cells(_gl_work(("uploaded", "read_back"), 1e6))),
    ]
    rows.append(
        _Row("GL full render", columns.gl_cells(lambda c, r: _fmt_time(r["gl"]["full_render"]["median_s"])))
    )
    if have_jax:
        rows += _ratio_rows(columns)
    rows.append(_Row("GL status", [r.get("gl", {}).get("status", "-") for r in columns.results]))
    return rows


def _ratio_rows(columns: _Columns) -> list[_Row]:
    """JAX / GL full render, against both of its targets."""

    def ratio(target: str) -> list[str]:
        return columns.cells(
            lambda c, r: (
                f"{r['jax_over_gl']:.2f}x" + _mark(r["targets_met"].get(target)) if "jax_over_gl" in r else ""
            )
        )

    return [
        _Row(
            "JAX / GL full render",
            ratio("jax_over_gl"),
            f">= {GL_TARGET_RATIO:g}x at {FULL_RENDER_TARGET_CONFIG[0] // 1000}k @ "
            f"{FULL_RENDER_TARGET_CONFIG[1]}, 64 maps (GL no slower than JAX)",
        ),
        _Row(
            "  JAX no slower than GL",
            ratio("jax_no_slower_than_gl"),
            f"<= {JAX_TARGET_RATIO:g}x at "
            + " and ".join(f"{n // 1000}k @ {s}" for n, s in JAX_TARGET_CONFIGS)
            + " (the geometry stage on the device)",
        ),
    ]


def _peak_rss_row(results: list[dict]) -> _Row:
    """Each run's peak resident memory, against its target."""
    return _Row(
        "peak RSS",
        [
            f"{r['peak_rss_kib'] / 1024**2:.2f} GiB" + _mark(r.get("targets_met", {}).get("peak_rss"))
            if r.get("peak_rss_kib")
            else "-"
            for r in results
        ],
        f"<= {PEAK_RSS_TARGET_GIB:g} GiB at {config_name(_target_config())}",
    )


def _aligned(header: str, names: list[str], rows: list[_Row]) -> list[str]:
    """The header, then the rows under a head line, each column as wide as its widest cell:
    labels and targets left-aligned, figures right-aligned."""
    head = _Row("stage", names, "target")
    widths = [max(len(head.label), *(len(r.label) for r in rows))]
    for j in range(len(names)):
        widths.append(max(len(names[j]), *(len(r.cells[j]) for r in rows)))
    widths.append(max(len(head.target), *(len(r.target) for r in rows)))

    def line(row: _Row) -> str:
        parts = [row.label.ljust(widths[0])]
        parts += [v.rjust(w) for v, w in zip(row.cells, widths[1:-1])]
        parts.append(row.target.ljust(widths[-1]))
        return "  ".join(parts).rstrip()

    return [header, "", line(head), "  ".join("-" * w for w in widths), *(line(r) for r in rows)]


def _error_lines(names: list[str], results: list[dict]) -> list[str]:
    """After a blank line, each failed run's error and each failed GL run's, by configuration."""
    errors = [(n, r["error"]) for n, r in zip(names, results) if r.get("error")]
    errors += [(n, r["gl"]["error"]) for n, r in zip(names, results) if r.get("gl", {}).get("error")]
    return ["", *(f"{n}: {e}" for n, e in errors)] if errors else []


def _finite_or_none(x):
    """JSON has no NaN or infinity: such figures are written as null."""
    if isinstance(x, float) and not math.isfinite(x):
        return None
    if isinstance(x, dict):
        return {k: _finite_or_none(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_finite_or_none(v) for v in x]
    return x


def write_json_strict(path: Path, data) -> None:
    """Write JSON atomically; non-finite numbers become null (strict JSON)."""
    write_json(path, _finite_or_none(data), allow_nan=False)
