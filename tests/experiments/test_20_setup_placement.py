"""experiments/20_setup_placement.py runs end to end (docs/model.md §5)."""

from __future__ import annotations

import json
import os
from pathlib import Path

from helpers import load_experiment

from hairjax._geometry._device_raster import SETUP_PLACEMENT

SCENE = Path(__file__).resolve().parents[2] / "experiments" / "scenes" / "grazing.toml"


def test_setup_placement_runs(tmp_path, monkeypatch):
    monkeypatch.setenv(SETUP_PLACEMENT, "host")
    out = tmp_path / "placement.json"
    assert load_experiment("20_setup_placement").main([str(SCENE), "--json", str(out)]) == 0
    row = json.loads(out.read_text())["scenes"]["grazing"]
    # The same fragments, composited by the same programs: the same image.
    assert row["same_fragments"] is True and row["fragments"] > 1000
    assert row["max_abs"] == 0.0
    assert row["host_s"] > 0 and row["device_s"] > 0
    assert os.environ[SETUP_PLACEMENT] == "host"  # the experiment puts the placement back
