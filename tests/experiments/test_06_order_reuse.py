"""experiments/06_order_reuse.py runs end to end in quick mode (kim-2003 Fig. 8's reused order)."""

from __future__ import annotations

import csv
import math

import numpy as np
from helpers import load_experiment


def test_order_reuse_quick(tmp_path, capsys):
    out = tmp_path / "out"
    assert load_experiment("06_order_reuse").main(["--quick", "--no-gl", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    with open(out / "order_reuse.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [float(r["angle"]) for r in rows] == [0.0, 10.0, 30.0]
    assert {r["path"] for r in rows} == {"jax"}
    for r in rows:
        for key in ("rmse", "max_abs", "frac_visible"):
            assert math.isfinite(float(r[key])) and float(r[key]) >= 0, (r, key)
    # At 0° the reused order is the order: the images are identical.
    zero = rows[0]
    assert float(zero["rmse"]) == 0.0 and float(zero["max_abs"]) == 0.0
    with open(out / "order_reuse_timings.csv", newline="") as f:
        (timing,) = list(csv.DictReader(f))
    assert float(timing["order_s"]) > 0 and float(timing["render_jax_s"]) > 0
    assert (out / "order_reuse.png").stat().st_size > 0
    assert "JAX render" in printed


def test_turned_camera_keeps_distance_height_and_target():
    import hairjax as hj

    module = load_experiment("06_order_reuse")
    scene = hj.Scene(
        hj.furball(10, 3, seed=0), camera=hj.Camera(eye=(1.0, 0.5, 4.0), target=(1.0, -0.1, 0.0))
    )
    view = module.turned(scene, 90.0)
    # By hand: turning (0, 0.6, 4) about y by +90° gives (4, 0.6, 0) (x = sin·z, z = cos·z).
    np.testing.assert_allclose(view.camera.eye, (1.0 + 4.0, 0.5, 0.0), atol=1e-12)
    assert view.camera.target == scene.camera.target and view.strands is scene.strands
    np.testing.assert_allclose(module.turned(scene, 0.0).camera.eye, scene.camera.eye, atol=0)


def test_image_difference_by_hand():
    module = load_experiment("06_order_reuse")
    a = np.zeros((2, 2, 4))
    b = np.zeros((2, 2, 4))
    b[0, 0, 1] = 0.2  # one channel of one pixel
    b[1, 1, 3] = 0.9  # alpha is not compared
    d = module.image_difference(a, b)
    assert math.isclose(d["max_abs"], 0.2) and math.isclose(d["rmse"], math.sqrt(0.04 / 12))
    assert d["frac_visible"] == 0.25
