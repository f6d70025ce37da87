"""experiments/15_sweep_vs_reference.py runs end to end (docs/physically_based.md §2, "Quality
settings against the physically based reference")."""

from __future__ import annotations

import csv
import json

import pytest
from helpers import load_experiment

pytest.importorskip("mitsuba", reason="the reference needs Mitsuba 3 (pip install 'hairjax[reference]')")


@pytest.mark.slow
def test_sweep_against_the_reference_runs(tmp_path, capsys):
    assert load_experiment("15_sweep_vs_reference").main(["--quick", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "Cheapest settings within 10% of the best error" in out
    fit = json.loads((tmp_path / "fit.json").read_text())
    assert fit["loss"][-1] < fit["loss"][0]  # the fit moved towards the Mitsuba target
    config = json.loads((tmp_path / "sweep.json").read_text())
    assert set(config["reference"]) == {"target"}
    points = [json.loads(line) for line in (tmp_path / "points.jsonl").read_text().splitlines()]
    assert len(points) == 4 and all(p["rel_rmse"] > 0 and p["tau_rmse"] is None for p in points)
    with open(tmp_path / "mitsuba_cost.csv") as f:
        cost = list(csv.DictReader(f))
    assert [int(c["spp"]) for c in cost] == [4, 16]
    # Monte Carlo noise falls at least as 1/√spp (the stratified sampler only does better,
    # 3.4× measured here): 4× the samples, at least half the noise, less a 1.5× margin for
    # the estimate from one 24² pair of images.
    ratio = float(cost[0]["noise_rmse"]) / float(cost[1]["noise_rmse"])
    assert ratio > 2 / 1.5
    assert (tmp_path / "against_reference.png").read_bytes()[:4] == b"\x89PNG"
