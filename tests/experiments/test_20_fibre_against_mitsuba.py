"""experiments/20_fibre_against_mitsuba.py in quick mode: the table has its cases, and each
ratio is near 1 (front-lit within 15 %, back-lit within 35 %: the 96² figures of
docs/model.md §19, 0.97–1.05 and 1.12–1.22, with 16 spp noise at 32²)."""

from __future__ import annotations

import pytest
from helpers import load_experiment

pytest.importorskip("mitsuba", reason="the Mitsuba reference is the optional extra hairjax[reference]")


@pytest.mark.slow
def test_quick_table(capsys):
    module = load_experiment("20_fibre_against_mitsuba")
    assert module.main(["--quick"]) == 0
    rows = [
        line
        for line in capsys.readouterr().out.splitlines()
        if line.startswith("| front") or line.startswith("| behind")
    ]
    assert len(rows) == 2, rows
    for row in rows:
        cells = [c.strip() for c in row.strip("|").split("|")]
        bound = 0.15 if cells[0] == "front" else 0.35
        for cell in cells[3:]:
            ratios = [float(x) for x in cell.split(",")]
            assert all(abs(r - 1.0) < bound for r in ratios), row
