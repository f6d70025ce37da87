"""The output of `hairjax bench`: the table it prints and its strict JSON (no NaN)."""

from __future__ import annotations

import math
from pathlib import Path

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


def format_table(configs: list[dict], results: list[dict], header: str) -> str:
    names = [config_name(c) for c in configs]
    rows: list[tuple[str, list[str], str]] = []

    def cells(fn):
        out = []
        for cfg, r in zip(configs, results):
            out.append(fn(cfg, r) if r.get("status") == "ok" else "")
        return out

    def stage(key):
        return lambda c, r: _fmt_time(r["stages"].get(key, {}).get("median_s"))

    have_jax = any("stages" in r for r in results)
    have_gl = any("gl" in r for r in results)

    def jax_cells(fn):
        return cells(lambda c, r: fn(c, r) if "stages" in r else "")

    def gl_cells(fn):
        return cells(lambda c, r: fn(c, r) if r.get("gl", {}).get("status") == "ok" else "")

    substeps = []
    for r in results:
        for key in r.get("stages", {}):
            if key.startswith("geometry_setup/") and key not in substeps:
                substeps.append(key)

    if have_jax:
        rows.append((STAGE_LABELS["geometry_setup"], jax_cells(stage("geometry_setup")), ""))
        for key in substeps:
            rows.append(("  " + key.split("/", 1)[1], jax_cells(stage(key)), ""))
        rows.append((STAGE_LABELS["geometry_opacity"], jax_cells(stage("geometry_opacity")), ""))
        rows.append(
            (
                STAGE_LABELS["shading"],
                jax_cells(
                    lambda c, r: (
                        _fmt_time(r["stages"]["shading"]["median_s"])
                        + _mark(r["targets_met"].get("shading_s"))
                    )
                ),
                f"<= {TARGETS['shading_s'] * 1e3:.0f} ms",
            )
        )
        rows.append((STAGE_LABELS["gradient"], jax_cells(stage("gradient")), ""))
        rows.append(
            (
                "  gradient / shading",
                jax_cells(
                    lambda c, r: (
                        f"{r['gradient_over_shading']:.2f}x"
                        + _mark(r["targets_met"].get("gradient_over_shading"))
                    )
                ),
                f"<= {TARGETS['gradient_over_shading']:g}x",
            )
        )
        rows.append(
            (
                STAGE_LABELS["full_render"],
                jax_cells(
                    lambda c, r: (
                        _fmt_time(r["stages"]["full_render"]["median_s"])
                        + _mark(r["targets_met"].get("full_render_s"))
                    )
                ),
                f"<= {TARGETS['full_render_s']:g} s at "
                f"{FULL_RENDER_TARGET_CONFIG[0] // 1000}k @ {FULL_RENDER_TARGET_CONFIG[1]}",
            )
        )
        rows.append(
            (
                "ordering (M segments/s)",
                jax_cells(
                    lambda c, r: (
                        f"{r['ordering']['msegments_per_s']:.1f}"
                        + _mark(r["targets_met"].get("ordering_msegments_per_s"))
                    )
                ),
                f">= {TARGETS['ordering_msegments_per_s']:g}",
            )
        )
        rows.append(
            (
                "  speed-up over kim-2003",
                jax_cells(lambda c, r: f"{r['ordering']['speedup_over_kim_2003']:.0f}x"),
                "(0.7 M/s, P-III 700 MHz)",
            )
        )
        rows.append(("  segments ordered", jax_cells(lambda c, r: f"{r['ordering']['segments']:,}"), ""))
        rows.append(("camera fragments", jax_cells(lambda c, r: f"{r['fragments']:,}"), ""))
        rows.append(
            (
                "shadow-map fragments",
                jax_cells(
                    lambda c, r: "-" if r["shadow_fragments"] is None else f"{r['shadow_fragments']:,}"
                ),
                "",
            )
        )
    if have_gl:
        for key in GL_PASSES:
            rows.append(
                (
                    f"GL {key}",
                    gl_cells(lambda c, r, key=key: _fmt_time(r["gl"]["passes"].get(key, {}).get("median_s"))),
                    "",
                )
            )
        rows.append(
            ("GL full render", gl_cells(lambda c, r: _fmt_time(r["gl"]["full_render"]["median_s"])), "")
        )
        if have_jax:

            def ratio(target):
                """JAX / GL full render, marked against `target` (a key of targets_met)."""
                return cells(
                    lambda c, r: (
                        f"{r['jax_over_gl']:.2f}x" + _mark(r["targets_met"].get(target))
                        if "jax_over_gl" in r
                        else ""
                    )
                )

            rows.append(
                (
                    "JAX / GL full render",
                    ratio("jax_over_gl"),
                    f">= {GL_TARGET_RATIO:g}x at {FULL_RENDER_TARGET_CONFIG[0] // 1000}k @ "
                    f"{FULL_RENDER_TARGET_CONFIG[1]}, 64 maps (GL no slower than JAX)",
                )
            )
            rows.append(
                (
                    "  JAX no slower than GL",
                    ratio("jax_no_slower_than_gl"),
                    f"<= {JAX_TARGET_RATIO:g}x at "
                    + " and ".join(f"{n // 1000}k @ {s}" for n, s in JAX_TARGET_CONFIGS)
                    + " (the geometry stage on the device)",
                )
            )
        rows.append(("GL status", [r.get("gl", {}).get("status", "-") for r in results], ""))
    rows.append(
        (
            "peak RSS",
            [
                f"{r['peak_rss_kib'] / 1024**2:.2f} GiB" + _mark(r.get("targets_met", {}).get("peak_rss"))
                if r.get("peak_rss_kib")
                else "-"
                for r in results
            ],
            f"<= {PEAK_RSS_TARGET_GIB:g} GiB at {config_name(_target_config())}",
        )
    )
    rows.append(("status", [r.get("verdict", r.get("status", "?")) for r in results], ""))

    head = ("stage", names, "target")
    widths = [max(len(head[0]), *(len(r[0]) for r in rows))]
    for j in range(len(names)):
        widths.append(max(len(names[j]), *(len(r[1][j]) for r in rows)))
    widths.append(max(len(head[2]), *(len(r[2]) for r in rows)))

    def line(label, values, target):
        parts = [label.ljust(widths[0])]
        parts += [v.rjust(w) for v, w in zip(values, widths[1:-1])]
        parts.append(target.ljust(widths[-1]))
        return "  ".join(parts).rstrip()

    out = [header, "", line(*head), "  ".join("-" * w for w in widths)]
    out += [line(*r) for r in rows]
    errors = [(n, r["error"]) for n, r in zip(names, results) if r.get("error")]
    errors += [(n, r["gl"]["error"]) for n, r in zip(names, results) if r.get("gl", {}).get("error")]
    if errors:
        out.append("")
        out += [f"{n}: {e}" for n, e in errors]
    return "\n".join(out)


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
