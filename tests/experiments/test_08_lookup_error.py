"""experiments/08_lookup_error.py runs end to end on a tiny scene, both renderers: the lookup
table's error against the analytic model shrinks with the table's size (docs/model.md §14)."""

import csv

import pytest
from helpers import load_experiment


@pytest.mark.slow
def test_lookup_error_experiment_runs(tmp_path, capsys, gl):
    """experiments/08_lookup_error.py end to end on a tiny scene, both renderers."""
    scene = tmp_path / "tiny.toml"
    scene.write_text('[hair]\nsource = "furball"\nstrands = 200\npoints = 6\n[shadows]\nmethod = "none"\n')
    out = tmp_path / "out"
    status = load_experiment("08_lookup_error").main(
        [
            "--scene",
            str(scene),
            "--size",
            "32",
            "--sizes",
            "4,64",
            "--repeats",
            "1",
            "--gl",
            "--out",
            str(out),
        ]
    )
    assert status == 0 and "GL RMSE" in capsys.readouterr().out
    with open(out / "lookup_error.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [int(r["size"]) for r in rows] == [4, 64]
    # A 16× finer table errs less (O(h) RMSE, tests/shading/test_lookup.py's
    # test_lookup_converges_to_the_formula), in both renderers.
    for key in ("rmse", "gl_rmse"):
        assert float(rows[1][key]) < float(rows[0][key]) / 4, key
    assert (out / "lookup_error.png").stat().st_size > 0
