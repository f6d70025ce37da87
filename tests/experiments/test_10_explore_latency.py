"""experiments/10_explore_latency.py runs end to end in quick mode (the latency of
hairjax.explore's sliders, BENCHMARKS.md "Live exploration")."""

from __future__ import annotations

import json
import math

import pytest
from helpers import load_experiment

pytest.importorskip("ipywidgets")


@pytest.mark.slow
def test_explore_latency_quick(tmp_path, capsys):
    out = tmp_path / "explore.json"
    assert load_experiment("10_explore_latency").main(["--quick", "--json", str(out)]) == 0
    result = json.loads(out.read_text())
    for key in ("panel built", "shading move", "  shading stage", "  PNG", "light move"):
        assert math.isfinite(result[key]) and result[key] > 0, key
    # --quick: 3 timed shading moves after 2 warm-up ones, 1 light move after 1 warm-up.
    assert len(result["moves"]["shading"]) == 3 and len(result["moves"]["light"]) == 1
    # The geometry stage ran once when the panel was built and once per light move, never
    # for a shading move: the figures time what the panel claims to do.
    assert result["geometry_runs"] == 1 + 2
    assert "shading move" in capsys.readouterr().out
