"""Folders written by the sweep before it became the joint search's engine over a one-knob
space (hairjax/tools/_search.py, _store.py): their files, copied here as that code wrote
them, resume through the command line, or are refused in one line when they hold other
settings."""

import json

import numpy as np
import pytest

import hairjax as hj
import hairjax.tools._search as search_mod
from hairjax import cli
from hairjax.tools import load_points
from hairjax.tools._measure import scene_digest

TOML = (
    'name = "tiny"\n[hair]\nsource = "furball"\nstrands = 30\npoints = 5\n'
    "[camera]\nwidth = 16\nheight = 16\n"
    '[shadows]\nmethod = "opacity-maps"\nmaps = 4\nresolution = 16\n'
)
# sweep.json as the sweep wrote it (no `timing`, no `search`), the digest filled in.
OLD_CONFIG = """{
  "scene": "tiny",
  "scene_digest": "%s",
  "repeats": %d,
  "reference": {
    "shadows": "exact at 16\\u00b2",
    "ordering": "exact",
    "supersampling": 1
  },
  "knobs": {
    "bins": [
      1,
      16,
      "exact"
    ]
  },
  "paths": [
    "jax"
  ],
  "size": [
    16,
    16
  ]
}"""
# One finished point as it was written (no `wall_s`), then a line cut short by a kill.
OLD_POINT = (
    '{"path": "jax", "knob": "bins", "value": 1, "time_s": 0.0103, "times": [0.0103], '
    '"rmse": 0.0247, "max_abs": 0.2358, "rel_rmse": 0.0431, "tau_rmse": 0.1189, "tau_max": 0.4449}'
)
CUT = '{"path": "jax", "knob": "bins", "val'
PEAK = 0.5  # the stored reference: grey 0.5 everywhere, Ω = 0 at every strand point


def _old_folder(tmp_path, repeats=1):
    toml = tmp_path / "tiny.toml"
    toml.write_text(TOML)
    scene = hj.load_scene(toml)
    out = tmp_path / "old"
    out.mkdir()
    (out / "sweep.json").write_text(OLD_CONFIG % (scene_digest(scene), repeats))
    (out / "points.jsonl").write_text(OLD_POINT + "\n" + CUT)
    with open(out / "reference_jax.npz", "wb") as f:
        image = np.full((16, 16, 4), PEAK)
        np.savez(f, image=image, omega=np.zeros(len(scene.strands.points)), peak=PEAK, time_s=0.2)
    return toml, scene, out


def test_an_old_sweep_folder_resumes(tmp_path, capsys):
    toml, scene, out = _old_folder(tmp_path)
    reference = (out / "reference_jax.npz").read_bytes()
    argv = ["sweep", str(toml), "--out", str(out), "--paths", "jax", "--knobs", "bins", "--quick"]
    assert cli.main([*argv, "--repeats", "1", "--quiet"]) == 0
    capsys.readouterr()
    lines = (out / "points.jsonl").read_text().splitlines()
    assert lines[0] == OLD_POINT and len(lines) == 3  # the finished point kept as written
    new = json.loads(lines[1])
    assert (new["path"], new["knob"], new["value"]) == ("jax", "bins", 16) and "settings" not in new
    # Measured against the folder's reference, not a new one: the RMSE against grey 0.5, over
    # its peak 0.5; the reference file is untouched.
    image = np.asarray(hj.render(scene.replace(ordering=hj.Ordering("bins", 16))), np.float64)
    expected = np.sqrt(np.mean((image[..., :3] - PEAK) ** 2))
    np.testing.assert_allclose(new["rmse"], expected, rtol=1e-9)  # one float64 sum, two orders
    assert new["rel_rmse"] == new["rmse"] / PEAK
    assert (out / "reference_jax.npz").read_bytes() == reference
    # The report holds the old point's values as stored.
    summary = (out / "summary.md").read_text()
    assert "| jax | bins | 1 | 0.0103 | 0.0247 | 0.0431 | 0.236 | 0.119 | 0.445 |" in summary
    assert [p["value"] for p in load_points(out)] == [1, 16, "exact"]


@pytest.mark.parametrize(
    "extra, repeats, message",
    [
        ([], 3, "holds a sweep of other settings (tiny, repeats 3); choose another --out or pass --restart"),
        (["--joint"], 1, "holds another kind of sweep (sweep.json); choose another --out"),
    ],
)
def test_an_old_sweep_folder_of_other_settings_is_refused_in_one_line(
    tmp_path, capsys, monkeypatch, extra, repeats, message
):
    toml, _, out = _old_folder(tmp_path, repeats=repeats)

    def no_render(path):
        raise AssertionError("a renderer was made for a refused folder")

    monkeypatch.setattr(search_mod, "renderer", no_render)
    argv = ["sweep", str(toml), "--out", str(out), "--paths", "jax", "--knobs", "bins", "--quick"]
    assert cli.main([*argv, "--repeats", "1", *extra]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"hairjax: error: {out} {message}", err
    assert (out / "points.jsonl").read_text() == OLD_POINT + "\n" + CUT  # nothing rewritten
