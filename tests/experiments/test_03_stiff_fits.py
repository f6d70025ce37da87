"""experiments/03_stiff_fits.py runs end to end in quick mode (no timing or accuracy thresholds
beyond what hairjax.fit guarantees)."""

from __future__ import annotations

import csv
import math

import pytest
from helpers import load_experiment


@pytest.mark.slow
def test_stiff_fits_quick(tmp_path, capsys):
    module = load_experiment("03_stiff_fits")
    out = tmp_path / "out"
    assert module.main(["--quick", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    with open(out / "stiff_fits.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    # The quick mode's cases, one solver each.
    assert sorted(r["case"] for r in rows) == ["ks-zero-held", "start-x100"]
    for r in rows:
        assert r["termination"].strip(), r
        assert r["status"].strip(), r
        assert math.isfinite(float(r["rmse"])), r
        assert int(r["steps"]) >= 0
    # With Ks held at 0 the image does not depend on the shininess at all: hj.fit reports it
    # undetermined (as tests/fit/test_fit.py::test_shininess_undetermined_without_specular).
    held = next(r for r in rows if r["case"] == "ks-zero-held")
    assert "shininess" in held["undetermined"].split()
    assert "ks" not in held["fitted"].split()
    table = (out / "stiff_fits.md").read_text()
    assert "| ks-zero-held |" in table and "| start-x100 |" in table
    assert "failure(s)" in table and "| ks-zero-held |" in printed


def test_judge_statuses():
    """The status rules of the docstring, on hand-made results."""
    judge = load_experiment("03_stiff_fits").judge
    fitted = ("kd", "ks", "shininess", "kappa")
    good = dict(kd=1e-4, ks=2e-3, shininess=5e-3, kappa=1e-5)
    assert judge("converged", good, fitted, (), (), 1e-2) == ("converged", False, 5e-3)
    status, failure, worst = judge("converged", {**good, "kd": 0.3}, fitted, (), (), 1e-2)
    assert status.startswith("wrong:") and "kd" in status and failure and worst == 0.3
    # An undetermined parameter is not judged by its error, but unexpected it is a failure.
    status, failure, _ = judge("converged", {**good, "ks": 1.0}, fitted, ("ks",), (), 1e-2)
    assert status.startswith("wrong:") and "ks undetermined" in status and failure
    status, failure, _ = judge(
        "converged", {**good, "shininess": 50.0}, fitted, ("shininess",), ("shininess",), 1e-2
    )
    assert status == "converged" and not failure
    # Undetermined but at the truth (Ks → 0 when the truth is 0): not wrong.
    status, failure, worst = judge("converged", good, fitted, ("ks",), (), 1e-2)
    assert status == "converged" and not failure and worst == 5e-3
    # A clear stop is not a failure, even off the truth; a missing expected flag is noted.
    status, failure, _ = judge(
        "stopped: reached max_steps = 9", {**good, "kd": 0.3}, fitted, (), ("shininess",), 1e-2
    )
    assert status.startswith("stopped: reached max_steps") and "not reported undetermined" in status
    assert not failure
    # A NaN error is never "within the bound".
    status, failure, _ = judge("converged", {**good, "kappa": math.nan}, fitted, (), (), 1e-2)
    assert failure


def test_parameter_errors_absolute_at_zero_truth():
    import hairjax as hj

    errors = load_experiment("03_stiff_fits").parameter_errors
    truth = hj.ShadingParams(kd=(0.5, 0.25, 0.2), ks=0.0, shininess=100.0, kappa=2.0)
    fitted = hj.ShadingParams(kd=(0.5, 0.5, 0.2), ks=0.003, shininess=101.0, kappa=2.0)
    e = errors(fitted, truth)
    # By hand: Kd's worst channel is 0.25 off 0.25; Ks is absolute where the truth is 0.
    assert math.isclose(e["kd"], 1.0) and math.isclose(e["ks"], 0.003, rel_tol=1e-6)
    assert math.isclose(e["shininess"], 0.01, rel_tol=1e-6) and e["kappa"] == 0.0
