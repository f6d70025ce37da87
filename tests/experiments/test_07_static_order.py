"""experiments/07_static_order.py runs end to end in quick mode (scheuermann-2004 slide 14's
static order against per-view bin sorts)."""

from __future__ import annotations

import csv
import math

from helpers import load_experiment


def test_static_order_quick(tmp_path, capsys):
    out = tmp_path / "out"
    assert load_experiment("07_static_order").main(["--quick", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    with open(out / "static_order.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    methods = {(r["method"], int(r["bins"])) for r in rows}
    assert methods == {("static", 0), ("bins", 4), ("bins", 16), ("reused", 256), ("none", 0)}
    assert sorted({float(r["angle"]) for r in rows}) == [0.0, 90.0, 180.0]
    for r in rows:
        for key in ("rmse", "max_abs", "frac_visible"):
            assert math.isfinite(float(r[key])) and float(r[key]) >= 0, (r, key)
    # On a ball seen from outside, finer bins are nearer the exact order (kim-2003 §3: fewer
    # misordered pairs): 16 bins beat 4 at every angle, and at 0° the reused order, a
    # 256-bin sort of that very view, beats 16. Checks that the errors measure the order.
    by = {(r["method"], int(r["bins"]), float(r["angle"])): float(r["rmse"]) for r in rows}
    assert all(by[("bins", 16, a)] < by[("bins", 4, a)] for a in (0.0, 90.0, 180.0))
    assert by[("reused", 256, 0.0)] < by[("bins", 16, 0.0)]
    with open(out / "static_order_timings.csv", newline="") as f:
        timings = list(csv.DictReader(f))
    assert {t["method"] for t in timings} == {"exact", "static", "bins", "reused"}
    assert all(float(t["order_s"]) > 0 for t in timings)
    assert {t["when"] for t in timings if t["method"] in ("static", "reused")} == {"once"}
    assert (out / "static_order.png").stat().st_size > 0
    assert "RMSE med" in printed
