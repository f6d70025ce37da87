"""experiments/11_cli_latency.py runs end to end (BENCHMARKS.md "Command line start-up")."""

from __future__ import annotations

import json
import math

import pytest
from helpers import load_experiment


@pytest.mark.slow
def test_cli_latency_runs(tmp_path, capsys):
    out = tmp_path / "cli.json"
    assert load_experiment("11_cli_latency").main(["--repeats", "1", "--json", str(out)]) == 0
    medians = json.loads(out.read_text())
    assert set(medians) == {
        "hairjax --help",
        "hairjax render --help",
        "hairjax --version",
        "import hairjax; hairjax.render",
    }
    assert all(math.isfinite(v) and v > 0 for v in medians.values())
    assert "hairjax --help" in capsys.readouterr().out
