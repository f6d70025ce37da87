"""Smoke test of `hairjax bench --quick`: it runs, and its JSON holds every figure.

No timing thresholds: the targets are printed by the benchmark, not asserted here.
"""

from __future__ import annotations

import json
import math

from hairjax._bench import STAGES
from hairjax.cli import main


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
