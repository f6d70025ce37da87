"""experiments/19_device_images.py runs end to end (BENCHMARKS.md "GPU: one NVIDIA H200",
"The set-up on the device, built")."""

from __future__ import annotations

import json
import os
from pathlib import Path

import jax
import numpy as np
import pytest
from helpers import load_experiment

import hairjax as hj

SCENE = Path(__file__).resolve().parents[2] / "experiments" / "scenes" / "grazing.toml"


@pytest.mark.slow
def test_device_images_run(tmp_path, monkeypatch):
    monkeypatch.setenv("HAIRJAX_SETUP", "host")
    out = tmp_path / "images.json"
    argv = [str(SCENE), "--repeats", "1", "--json", str(out), "--images", str(tmp_path / "images")]
    assert load_experiment("19_device_images").main(argv) == 0
    data = json.loads(out.read_text())
    row = data["scenes"]["grazing"]
    if jax.default_backend() == "cpu":  # both images from the one CPU: the same program
        assert row["device_vs_cpu"] == 0.0
    assert data["worst"] <= data["tolerance"] == 1e-5
    # GL against JAX: within the scene's band where GL runs (docs/model.md §11), else None.
    assert row["gl_vs_device"] is None or 0.0 <= row["gl_vs_device"] < 0.1
    # The two set-ups write the same fragments, composited by the same programs.
    setup = row["setup"]
    assert setup["same_fragments"] is True and setup["fragments"] > 1000
    assert setup["max_abs"] == 0.0
    assert setup["host_s"] > 0 and setup["device_s"] > 0
    assert os.environ["HAIRJAX_SETUP"] == "host"  # the experiment names its placements, writes none
    # The images, and where GL ran their difference, as read back.
    jax_image = hj.read_image(tmp_path / "images" / "grazing_jax.exr")
    assert jax_image.shape[2] == 4 and np.all(np.isfinite(jax_image))
    if row["gl_vs_device"] is not None:
        diff = hj.read_image(tmp_path / "images" / "grazing_diff.exr")
        assert abs(float(diff.max()) - row["gl_vs_device"]) <= 1e-6  # float32 EXR of the same difference
