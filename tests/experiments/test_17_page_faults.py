"""experiments/17_page_faults.py runs end to end (BENCHMARKS.md "Fresh pages")."""

from __future__ import annotations

import re

from helpers import load_experiment


def test_page_faults_runs(capsys):
    argv = ["--strands", "200", "--size", "32", "--repeats", "1", "--probe-mib", "4"]
    assert load_experiment("17_page_faults").main(argv) == 0
    out = capsys.readouterr().out
    assert "200 strands at 32²" in out
    faults = int(re.search(r"minor page faults per render +(\d+)", out).group(1))
    fresh = float(re.search(r"a fault, fresh mapping +([0-9.]+) us", out).group(1))
    product = float(re.search(r"faults x cost +([0-9.]+) ms", out).group(1))
    # The product as printed, from its rounded factors (fault cost to 0.01 µs, result to 1 ms).
    assert abs(product - faults * fresh / 1e3) <= 0.5 + faults * 0.005 / 1e3
    assert float(re.search(r"share of the render: ([0-9.]+)$", out, flags=re.M).group(1)) >= 0
