"""experiments/18_device_figures.py runs end to end (BENCHMARKS.md "GPU: one NVIDIA H200")."""

from __future__ import annotations

import json

import pytest
from helpers import load_experiment


def test_device_figures_run(tmp_path, capsys):
    out = tmp_path / "figures.json"
    argv = ["--quick", "--bench", "300x32", "--skip", "fit,tressfx", "--repeats", "1", "--json", str(out)]
    assert load_experiment("18_device_figures").main(argv) == 0
    data = json.loads(out.read_text())
    assert data["status"] == "done" and data["errors"] == []
    case = data["bench"]["300 @ 32x32"]
    assert case["strands"] == 300 and case["jax"]["image_finite"]
    stages = case["jax"]["stages"]
    assert {"geometry set-up", "geometry opacity (JAX)", "shading"} <= set(stages)
    # The full render is its stages, each timed after the one before ended.
    parts = ("geometry set-up", "geometry opacity (JAX)", "shading")
    assert sum(stages[k]["median_s"] for k in parts) <= 1.5 * case["jax"]["full_render"]["median_s"]
    assert case["shading"]["median_s"] > 0 and case["jax"]["fragments"] > 0
    assert case["jax"]["shadow_fragments"] > 0  # the render's summed opacity maps count theirs
    # GL twice: ribbons by the geometry shader, then by vertex pulling.
    assert case["gl"]["status"] == case["gl_vertex_pulling"]["status"] == "ok"
    assert case["gl_vertex_pulling"]["full_render"]["median_s"] > 0
    assert "fit" not in data and "tressfx" not in data  # skipped sections leave no entry
    printed = capsys.readouterr().out
    assert "300 @ 32x32" in printed and "GL full render, ribbons by vertex pulling" in printed


@pytest.mark.slow
def test_device_figures_time_the_host_set_up_too_on_an_accelerator(tmp_path, monkeypatch, capsys):
    """With the set-up on the device (forced here on the CPU device, as a GPU's default),
    each fur ball is timed a second time with the set-up on the host, named as an argument:
    the default is left as it was."""
    import os

    monkeypatch.setenv("HAIRJAX_SETUP", "device")
    out = tmp_path / "figures.json"
    argv = ["--quick", "--bench", "300x32", "--skip", "fit,tressfx", "--repeats", "1", "--json", str(out)]
    assert load_experiment("18_device_figures").main(argv) == 0
    data = json.loads(out.read_text())
    assert data["machine"]["setup_placement"] == "device"
    case = data["bench"]["300 @ 32x32"]
    # The same fragments drawn; the device's set-up keeps a superset of the host's, which
    # keeps those seen through half the drawn cutoff (SETUP_MARGIN, docs/model.md §6).
    jax, host = case["jax"], case["jax_host_setup"]
    assert jax["drawn_fragments"] == host["drawn_fragments"] > 0
    assert jax["fragments"] >= host["fragments"] >= host["drawn_fragments"]
    assert jax["shadow_fragments"] == host["shadow_fragments"] > 0
    assert case["jax_host_setup"]["full_render"]["median_s"] > 0
    assert "full render, set-up on the host" in capsys.readouterr().out
    assert os.environ["HAIRJAX_SETUP"] == "device"
