"""experiments/16_deep_maps.py: its equal-time interpolation, and the script end to end on a
tiny fur ball (no timing thresholds)."""

from __future__ import annotations

import csv
import math

import pytest
from helpers import load_experiment


def _rows(*curve):
    return [{"scene": "s", "method": "opacity-maps", "shadow_s": t, "tau_rmse": e} for t, e in curve]


def test_at_equal_time_interpolates_in_log_log():
    deep = load_experiment("16_deep_maps")
    rows = _rows((0.01, 0.1), (0.1, 0.001))
    # Halfway in log time between 10 ms and 100 ms: halfway in log error, 0.01.
    assert deep.at_equal_time(rows, "s", math.sqrt(0.01 * 0.1), "tau_rmse") == pytest.approx(0.01)
    assert deep.at_equal_time(rows, "s", 0.01, "tau_rmse") == pytest.approx(0.1)
    assert deep.at_equal_time(rows, "s", 0.005, "tau_rmse") is None  # faster than the curve
    assert deep.at_equal_time(rows, "s", 0.2, "tau_rmse") is None  # slower than the curve
    assert deep.at_equal_time(rows, "other", 0.05, "tau_rmse") is None
    # A zero error (no logarithm): linear between the two settings.
    assert deep.at_equal_time(_rows((1.0, 0.2), (3.0, 0.0)), "s", 2.0, "tau_rmse") == pytest.approx(0.1)


def test_deep_maps_quick(tmp_path, capsys, gl):
    out = tmp_path / "out"
    assert load_experiment("16_deep_maps").main(["--quick", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "at the same shadow-pass time" in printed

    with open(out / "deep_maps.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    methods = [(r["method"], r["count"]) for r in rows]
    assert methods[0] == ("exact", "")
    assert ("opacity-maps", "64") in methods and ("deep", "4") in methods
    for r in rows:
        for key in ("shadow_s", "total_s", "tau_rmse", "tau_max", "rel_rmse"):
            assert math.isfinite(float(r[key])), (r, key)
        assert float(r["tau_rmse"]) <= float(r["tau_max"]) <= 1.0  # τ ∈ [0, 1]
    # Exact is its own reference; every approximation differs from it somewhere.
    assert float(rows[0]["tau_rmse"]) == 0.0 and float(rows[0]["rel_rmse"]) == 0.0
    assert all(float(r["tau_rmse"]) > 0 for r in rows[1:])
    maps = {int(r["count"]): float(r["tau_rmse"]) for r in rows if r["method"] == "opacity-maps"}
    # kim-2003 §4: more maps, a finer slicing, a smaller error (4 → 64 maps on 8-point strands).
    assert maps[64] < maps[4]
    for name in ("deep_maps_tiny.png", "deep_maps_tiny_stripes.png"):
        assert (out / name).read_bytes()[:4] == b"\x89PNG", name
