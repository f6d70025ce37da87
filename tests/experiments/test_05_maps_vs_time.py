"""experiments/05_maps_vs_time.py: its slope fit, and the script end to end on a tiny scene
(no timing thresholds)."""

from __future__ import annotations

import csv
import math

import pytest
from helpers import load_experiment

TINY_SCENE = """\
name = "tiny"

[hair]
source = "furball"
strands = 300
points = 8

[camera]
width = 64
height = 64

[shadows]
method = "opacity-maps"
maps = 4
resolution = 32
"""


def test_fit_slope():
    maps_vs_time = load_experiment("05_maps_vs_time")
    maps = [1, 2, 4, 8, 16, 32, 64]
    assert maps_vs_time.fit_slope(maps, [0.5 * n for n in maps]) == pytest.approx(1.0)
    assert maps_vs_time.fit_slope(maps, [n**0.5 for n in maps]) == pytest.approx(0.5)
    assert math.isnan(maps_vs_time.fit_slope([1, 16], [1.0, 2.0]))  # one point >= 16


def test_maps_vs_time_tiny(tmp_path, capsys, gl):
    scene = tmp_path / "tiny.toml"
    scene.write_text(TINY_SCENE)
    out = tmp_path / "out"
    status = load_experiment("05_maps_vs_time").main(
        ["--scene", str(scene), "--maps", "1,4", "--repeats", "1", "--out", str(out)]
    )
    assert status == 0
    printed = capsys.readouterr().out
    assert "slope" in printed

    with open(out / "maps_vs_time.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [int(r["maps"]) for r in rows] == [1, 4]
    for r in rows:
        for key in ("clipped_s", "unclipped_s", "clipped_shadows_s", "unclipped_shadows_s"):
            value = float(r[key])
            assert math.isfinite(value) and value > 0, (r["maps"], key)
    assert (out / "maps_vs_time.png").stat().st_size > 0
