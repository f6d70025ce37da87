"""Smoke tests of `hairjax bench --quick` (JAX, and `--backend both`): it runs, and its
JSON holds every figure.

No timing thresholds: the targets are printed by the benchmark, not asserted here.
"""

from __future__ import annotations

import json
import math
import statistics

import pytest

from hairjax.cli import main
from hairjax.tools import GL_PASSES, STAGES
from hairjax.tools._bench_report import format_table
from hairjax.tools._bench_timing import measure_gl


def _positive_finite(x) -> bool:
    return isinstance(x, (int, float)) and math.isfinite(x) and x > 0


def test_bench_quick_writes_every_figure(tmp_path, capsys):
    out = tmp_path / "b.json"
    status = main(["bench", "--quick", "--repeats", "2", "--json", str(out)])
    assert status == 0
    printed = capsys.readouterr().out
    assert "shading stage" in printed and "ordering" in printed

    data = json.loads(out.read_text())
    assert not list(tmp_path.glob(".b.json.*")), "the atomic write left a temporary file"
    assert data["repeats"] == 2
    for key in ("platform", "cpu_count", "jax_version", "jax_backend"):
        assert data["machine"][key], key

    (config,) = data["configurations"]
    assert config["status"] == "ok", config["error"]
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


def test_bench_quick_both_backends(tmp_path, capsys):
    out = tmp_path / "b.json"
    status = main(["bench", "--quick", "--repeats", "2", "--backend", "both", "--json", str(out)])
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
    assert "GL full render" in printed and "JAX / GL full render" in printed
    assert "JAX no slower than GL" in printed
    assert _positive_finite(gl["full_render"]["median_s"])
    assert len(gl["full_render"]["runs_s"]) == 2
    for key in GL_PASSES:
        assert _positive_finite(gl["passes"][key]["median_s"]), key
    assert gl["image_finite"]
    # The ratio is the median of back-to-back pairs' ratios, as recorded.
    paired = config["paired"]
    assert len(paired["gl_s"]) == len(paired["jax_s"]) == len(paired["ratios"]) == 2
    for j, g, r in zip(paired["jax_s"], paired["gl_s"], paired["ratios"]):
        assert _positive_finite(j) and _positive_finite(g) and r == pytest.approx(j / g, rel=1e-12)
    assert config["jax_over_gl"] == pytest.approx(statistics.median(paired["ratios"]), rel=1e-12)
    # The JAX figures are still all there.
    assert set(STAGES) <= set(config["stages"])


def test_bench_reports_gl_unavailable(monkeypatch):
    import hairjax.gl

    def unavailable():
        raise hairjax.gl.GLUnavailable("no EGL here")

    monkeypatch.setattr(hairjax.gl, "get_context", unavailable)
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
