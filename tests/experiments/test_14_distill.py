"""experiments/14_distill.py in quick mode: real-time models fitted to Mitsuba references.

The targets are path traced (Mitsuba 3, the `reference` extra), so the checks are on what
any fit must show: each fit lowers the RMSE below its start's, reports a finite held-out
RMSE, and every RMSE has its noise floor (two sample seeds) beside it."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import pytest
from helpers import load_experiment

pytest.importorskip("mitsuba", reason="the Mitsuba reference is the optional extra hairjax[reference]")


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("distill")
    module = load_experiment("14_distill")
    assert module.main(["--quick", "--out", str(out), "--docs", str(out / "docs")]) == 0
    # --docs carries the CSV of fitted parameters, the same file as the run's own.
    assert (out / "docs" / "distill.csv").read_bytes() == (out / "distill.csv").read_bytes()
    with open(out / "distill.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    return module, out, rows


@pytest.mark.slow
def test_distill_quick_fits(quick_run, capsys):
    module, out, rows = quick_run
    assert {r["model"] for r in rows} == set(module.QUICK["models"])
    for r in rows:
        start, train, held = (float(r[k]) for k in ("start_rmse", "train_rmse", "holdout_rmse"))
        floor_train, floor_held = float(r["floor_train"]), float(r["floor_holdout"])
        assert math.isfinite(held) and held > 0, r
        # The fit moves off its start: the pooled training RMSE drops clearly below it.
        assert train < 0.9 * start, r
        # Two sample seeds never agree exactly, so the floor is positive, and it is a
        # part of every RMSE (independent noise adds floor²/2 to a perfect model's RMSE²).
        assert 0 < floor_train < train and 0 < floor_held < held, r
        # The pooled training RMSE is the fit's, over the training views' renders.
        views = [v.name for v in module.VIEWS if v.train and v.name in module.QUICK["views"]]
        pooled = math.sqrt(sum(float(r[f"rmse_{v}"]) ** 2 for v in views) / len(views))
        assert pooled == pytest.approx(train, rel=0.02), r
        assert float(r[f"rmse_{module.VIEWS[-1].name}"]) == pytest.approx(held, rel=1e-3), r
        for name in module.FIT_NAMES[r["model"]]:
            assert f"{name} " in r["params"], r
    table = (out / "distill.md").read_text()
    assert "floor train / held-out" in table and "| furball | brown | 0.2 |" in table
    assert list((out / "figures").glob("distill_furball_brown_0.2_held-out.png"))


def test_fit_names_share_one_tuple():
    """A name every model fits (the strand opacity, once hj.fit takes it) is one edit."""
    module = load_experiment("14_distill")
    assert set(module.FIT_NAMES) == set(module.STARTS) == set(module.SHORT)
    for names in module.FIT_NAMES.values():
        assert names[-len(module.SHARED_NAMES) :] == module.SHARED_NAMES


def test_the_recovery_fits_only_the_hairs_parameters_and_is_asked_for_by_name():
    """The pigment-only models (docs/physically_based.md §3) hold the lobe weights and the
    tilt: they are not in the default sweep, and a direct-light run keeps its references
    apart from the full ones."""
    module = load_experiment("14_distill")
    pigments = [m for m in module.FIT_NAMES if m.endswith("-pigments")]
    assert pigments and not set(pigments) & set(module.MODELS)
    for m in pigments:
        assert set(module.FIT_NAMES[m]) == {"eumelanin", "pheomelanin", "longitudinal_roughness", "kappa"}
    assert module.shading_model("marschner-dual-pigments").multiple_scattering == "dual"
    assert module.shading_model("marschner-pigments").multiple_scattering == "none"
    base = module.asset_scene("furball", 16, 10, Path("."))
    paths = {
        depth: module.reference_path(
            module._parser().parse_args(["--max-depth", str(depth)]), "furball", base, "red", 0.2
        )
        for depth in (2, 16)
    }
    assert paths[2] != paths[16] and paths[2].name.endswith("_depth2.npz")
