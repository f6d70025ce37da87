"""Smoke tests of `hairjax bench --quick` (JAX, and `--backend both`): it runs, and its
JSON holds every figure; the status row and the line under the table follow the
targets' verdicts (and a quick run judges none); the header names JAX's device and GL's
renderer.

No timing thresholds: the targets are printed by the benchmark, not asserted here.
"""

from __future__ import annotations

import json
import math
import re
import statistics

import jax
import pytest

from hairjax._shading import shading_model_class, shading_model_names
from hairjax.cli import main
from hairjax.tools import GL_PASSES, STAGES
from hairjax.tools._bench_models import NO_GL, format_models_table, model_rows
from hairjax.tools._bench_report import QUICK_NOTE, format_table, verdict, verdict_line
from hairjax.tools._bench_timing import measure_gl


def _positive_finite(x) -> bool:
    return isinstance(x, (int, float)) and math.isfinite(x) and x > 0


@pytest.mark.slow
def test_bench_quick_writes_every_figure(tmp_path, capsys):
    out = tmp_path / "b.json"
    status = main(["bench", "--quick", "--repeats", "2", "--json", str(out)])
    assert status == 0
    printed = capsys.readouterr().out
    assert "shading stage" in printed and "ordering" in printed
    # A quick run judges no target: no verdict in the table, a status that says it ran, and why.
    assert not re.search(r"(ms|s|x|\d) (ok|MISS)\b", printed), printed  # a figure's mark, e.g. "2.7 ms ok"
    (status,) = [line for line in printed.splitlines() if line.startswith("status ")]
    assert status.split() == ["status", "ran"]
    assert QUICK_NOTE in printed.splitlines()
    kind = jax.devices()[0].device_kind
    assert f"{jax.default_backend()}, float" in printed  # float32, or float64 under x64
    assert f") on {len(jax.devices())} x {kind}, set-up on the " in printed

    data = json.loads(out.read_text())
    assert not list(tmp_path.glob(".b.json.*")), "the atomic write left a temporary file"
    assert data["repeats"] == 2
    for key in ("platform", "cpu_count", "jax_version", "jax_backend"):
        assert data["machine"][key], key
    assert data["machine"]["jax_device_kind"] == kind and isinstance(kind, str)
    assert data["targets_judged"] is False and data["targets_missed"] == []

    (config,) = data["configurations"]
    assert config["status"] == "ok", config["error"]
    assert config["verdict"] == "ran" and config["targets_met"] == {}
    assert config["strands"] == 2000 and config["width"] == config["height"] == 128
    stages = config["stages"]
    assert set(STAGES) <= set(stages)
    assert any(key.startswith("geometry_setup/") for key in stages)
    for key, stage in stages.items():
        assert _positive_finite(stage["median_s"]), key
        assert len(stage["runs_s"]) == 2, key
    assert _positive_finite(config["gradient_over_shading"])
    assert config["gradient_finite"] and config["image_finite"]
    assert _positive_finite(config["ordering"]["msegments_per_s"])
    assert config["ordering"]["segments"] == 2000 * 15
    assert config["fragments"] > 0
    assert config["peak_rss_kib"] > 0
    _check_model_costs(data["shading_models"], printed, gl=False)


def _model_line(printed: str, label: str) -> str:
    (line,) = [x for x in printed.splitlines() if x.startswith(label + "  ")]
    return line


def _check_model_costs(record: dict, printed: str, gl: bool, models=None) -> None:
    """The cost per shading model: a row per registered model (or per one of `models`) at
    its defaults and per declared variant, each with positive times, printed under its own
    title."""
    assert record["status"] == "ok", record.get("error")
    assert record["configuration"] == "2k @ 128x128" and record["strands"] == 2000
    assert "shading models: cost per model at 2k @ 128x128" in printed
    rows = record["models"]
    assert [r["label"] for r in rows] == [label for label, _, _ in model_rows(names=models)]
    assert {r["model"] for r in rows if not r["options"]} == set(models or shading_model_names())
    if models is None:
        assert "marschner (azimuthal=chiang, azimuthal_samples=16)" in [r["label"] for r in rows]
    for r in rows:
        for key in ("shading", "gradient"):
            assert _positive_finite(r[key]["median_s"]), (r["label"], key)
            assert len(r[key]["runs_s"]) == 2
        assert r["image_finite"] and r["gradient_finite"], r["label"]
        assert set(r["gradient_wrt"]) <= set(shading_model_class(r["model"]).fittable) and r["gradient_wrt"]
        line = _model_line(printed, r["label"])
        assert len(re.findall(r" \d+\.\d\dx", line)) == 2, line  # / kajiya-kay and gradient / shading
        cells = line.split()
        if not gl:
            assert "gl" not in r and NO_GL not in printed
        elif r["gl_id"] is None:
            assert r["gl"]["status"] == "no GL side" and cells[-1] == NO_GL, r["label"]
        else:
            assert r["gl"]["status"] == "ok", r["gl"]["error"]
            assert _positive_finite(r["gl"]["full_render"]["median_s"]), r["label"]
            assert cells[-1] == "ms" or cells[-1] == "s"


def test_model_rows_come_from_the_registry_and_the_declared_variants():
    """Every registered model at its defaults, then the variants whose options its class
    declares; a variant naming an option the class lacks is left out."""
    variants = (
        ("marschner", {"azimuthal": "chiang", "azimuthal_samples": 16}),
        ("kajiya-kay", {"no_such_option": 1}),
    )
    rows = model_rows(variants)
    assert [name for _, name, options in rows if not options] == list(shading_model_names())
    assert [(label, opts) for label, _, opts in rows if opts] == [
        (
            "marschner (azimuthal=chiang, azimuthal_samples=16)",
            {"azimuthal": "chiang", "azimuthal_samples": 16},
        )
    ]
    i = [label for label, _, _ in rows].index("marschner")
    assert rows[i + 1][0].startswith("marschner (")


def test_the_models_table_marks_a_model_without_gl():
    """A model without a GL side shows — in the GL column, one with it its GL frame, and
    the shading stage is also given relative to Kajiya-Kay's."""

    def row(label, shading, gradient, gl):
        return {
            "label": label,
            "shading": {"median_s": shading},
            "gradient": {"median_s": gradient},
            "gl": gl,
        }

    record = {
        "status": "ok",
        "models": [
            row("kajiya-kay", 0.010, 0.030, {"status": "ok", "full_render": {"median_s": 0.2}}),
            row("toy", 0.025, 0.050, {"status": "no GL side", "error": None}),
        ],
    }
    table = format_models_table(record, "both", "title")
    kk, toy = _model_line(table, "kajiya-kay"), _model_line(table, "toy")
    assert kk.split()[1:] == ["10.0", "ms", "1.00x", "30.0", "ms", "3.00x", "200.0", "ms"]
    assert toy.split()[1:] == ["25.0", "ms", "2.50x", "50.0", "ms", "2.00x", NO_GL]
    jax_only = format_models_table(record, "jax", "title")
    assert NO_GL not in jax_only and "GL frame" not in jax_only
    failed = format_models_table({"status": "MemoryError", "error": "killed"}, "both", "title")
    assert "MemoryError: killed" in failed


@pytest.mark.slow
def test_bench_quick_both_backends(tmp_path, capsys):
    out = tmp_path / "b.json"
    # The GL column on one model (every model's row is checked by the JAX-only test above).
    argv = ["bench", "--quick", "--repeats", "2", "--backend", "both", "--models", "kajiya-kay"]
    status = main([*argv, "--json", str(out)])
    assert status == 0
    printed = capsys.readouterr().out
    data = json.loads(out.read_text())
    assert data["backend"] == "both"
    (config,) = data["configurations"]
    assert config["status"] == "ok", config["error"]
    gl = config["gl"]
    if gl["status"] == "unavailable":
        assert "GL unavailable:" in printed
        pytest.skip(gl["error"])
    assert gl["status"] == "ok", gl["error"]
    renderer = data["machine"]["gl_renderer"]
    assert isinstance(renderer, str) and renderer == gl["gl_renderer"]
    assert f"GL: {renderer} ({gl['gl_version']})" in printed.splitlines()
    assert "GL full render" in printed and "JAX / GL full render" in printed
    assert "JAX no slower than GL" in printed
    assert _positive_finite(gl["full_render"]["median_s"])
    assert len(gl["full_render"]["runs_s"]) == 2
    for key in GL_PASSES:
        assert _positive_finite(gl["passes"][key]["median_s"]), key
    assert gl["image_finite"]
    # A warm run's GL work (hairjax/gl/_work.py) is recorded and printed: its draws, its
    # targets bound, what it uploads (Ω, the passes' index buffers) and reads back.
    work = gl["work"]
    assert work["draws"] > 0 and work["binds"] > 0 and work["read_back"] > 0
    assert 0 < work["uploaded"] and "draws / binds" in printed and "MB uploaded / read" in printed
    assert work["dispatches"] > 0 and work["barriers"] > 0 and "dispatches / barriers" in printed
    # The format of stored runs from before the counts: "-" in those cells.
    old = {**config, "gl": {k: v for k, v in gl.items() if k != "work"}}
    table = format_table([{"strands": config["strands"], "size": config["width"]}], [old], "")
    assert any(
        line.strip().startswith("draws / binds") and line.rstrip().endswith("-")
        for line in table.splitlines()
    )
    # The ratio is the median of back-to-back pairs' ratios, as recorded.
    paired = config["paired"]
    assert len(paired["gl_s"]) == len(paired["jax_s"]) == len(paired["ratios"]) == 2
    for j, g, r in zip(paired["jax_s"], paired["gl_s"], paired["ratios"]):
        assert _positive_finite(j) and _positive_finite(g) and r == pytest.approx(j / g, rel=1e-12)
    assert config["jax_over_gl"] == pytest.approx(statistics.median(paired["ratios"]), rel=1e-12)
    # The JAX figures are still all there.
    assert set(STAGES) <= set(config["stages"])
    _check_model_costs(data["shading_models"], printed, gl=True, models=("kajiya-kay",))


def test_bench_refuses_an_unknown_model_in_one_line(capsys):
    assert main(["bench", "--quick", "--models", "kajiya-kay,no-such-model"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--models takes registered shading models" in err[0], err
    assert "'kajiya-kay,no-such-model'" in err[0]


def test_bench_reports_gl_unavailable(monkeypatch):
    import hairjax.gl

    def unavailable():
        raise hairjax.gl.GLUnavailable("no EGL here")

    monkeypatch.setattr(hairjax.gl._context, "get_context", unavailable)  # what renderer_info asks
    r = measure_gl(None, 1, lambda msg: None)
    assert r == {"status": "unavailable", "error": "GL unavailable: no EGL here"}
    cfg = dict(strands=2000, size=128)
    table = format_table([cfg], [{"status": "ok", "gl": r}], "header")
    assert "GL status" in table and "unavailable" in table
    assert "GL unavailable: no EGL here" in table


def test_the_device_targets_are_marked():
    """JAX / GL <= 1 at 20k @ 512 and 100k @ 1024 (the geometry stage on the device) and
    peak RSS <= 3 GiB at 100k @ 1024 are marked ok or MISS from the figures, and only there."""
    from hairjax.tools._bench import _targets_met

    def result(ratio, rss_gib):
        return {"status": "ok", "jax_over_gl": ratio, "peak_rss_kib": int(rss_gib * 1024**2)}

    small, big, other = (
        dict(strands=20_000, size=512),
        dict(strands=100_000, size=1024),
        dict(strands=2000, size=128),
    )
    assert _targets_met(small, result(0.9, 5.0)) == {"jax_no_slower_than_gl": True}
    assert _targets_met(small, result(1.7, 5.0)) == {"jax_no_slower_than_gl": False}
    met = _targets_met(big, result(2.9, 4.99))
    assert met["jax_no_slower_than_gl"] is False and met["peak_rss"] is False
    assert _targets_met(big, result(1.0, 2.5))["peak_rss"] is True
    assert _targets_met(other, result(0.5, 9.0)) == {}
    configs = [small, big]
    results = [dict(result(1.7, 1.2), targets_met=_targets_met(small, result(1.7, 1.2)))]
    results.append(dict(result(2.9, 4.99), targets_met=_targets_met(big, result(2.9, 4.99))))
    table = format_table(configs, results, "header")
    (rss,) = [line for line in table.splitlines() if line.startswith("peak RSS")]
    assert "4.99 GiB MISS" in rss and "1.20 GiB MISS" not in rss and "1.20 GiB" in rss


def _judged(met: dict) -> dict:
    result = {"status": "ok", "targets_met": met}
    return dict(result, verdict=verdict(result, judged=True))


def test_the_status_follows_the_verdicts():
    """A configuration that missed a target is not `ok`: its status counts the misses, and
    the line under the table names each (configuration and target); all met is `ok`; a
    run that failed keeps its failure; an unjudged (quick) run says it ran."""
    small, big = dict(strands=20_000, size=512), dict(strands=100_000, size=1024)
    missed = _judged({"shading_s": True, "gradient_over_shading": False, "full_render_s": False})
    met = _judged({"shading_s": True, "peak_rss": True})
    assert missed["verdict"] == "MISS (2 of 3)" and met["verdict"] == "ok"
    assert verdict({"status": "MemoryError", "targets_met": {}}, judged=True) == "MemoryError"
    assert verdict({"status": "ok", "targets_met": {}}, judged=False) == "ran"

    table = format_table([small, big], [met, missed], "header")
    (status,) = [line for line in table.splitlines() if line.startswith("status ")]
    assert status.split() == ["status", "ok", "MISS", "(2", "of", "3)"]
    line = verdict_line([small, big], [met, missed], judged=True)
    assert line == (
        "targets: 2 of 5 missed: gradient / shading at 100k @ 1024x1024; full render at 100k @ 1024x1024"
    )
    assert verdict_line([small, big], [met, met], judged=True) == "targets: all 4 met"
    assert verdict_line([small], [met], judged=False) == QUICK_NOTE
