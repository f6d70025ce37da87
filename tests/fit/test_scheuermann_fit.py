"""hairjax.fit on Scheuermann scenes (docs/fitting.md, docs/model.md §17): every fittable
parameter recovered, what the fit refuses for this model, and `hairjax fit` on a
Scheuermann scene file. The model's own tests (terms, shifts, GL) are in
tests/shading/test_scheuermann.py."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import scheuermann_scene

import hairjax as hj
from hairjax._shading._scheuermann import ScheuermannParams

FIT_NAMES = (
    "kd",
    "primary_color",
    "primary_exponent",
    "primary_shift",
    "secondary_color",
    "secondary_exponent",
    "secondary_shift",
    "kappa",
)


@pytest.mark.slow
def test_fit_recovers_every_parameter():
    """hairjax.fit on a Scheuermann scene: from 20-100 % off, every fittable parameter back
    to 1e-8 relative on a noise-free float64 target (LM converges to ~1e-15; 1e-8 leaves
    room for the tolerance rtol = 1e-8), with finite standard errors and a JSON report."""
    import json

    scene = scheuermann_scene(size=16, strands=20)
    truth = scene.params
    target = np.asarray(hj.render(scene, truth))
    start = ScheuermannParams(
        kd=0.3,
        ambient=truth.ambient,
        primary_color=0.2,
        primary_exponent=15.0,
        primary_shift=0.0,
        secondary_color=0.2,
        secondary_exponent=14.0,
        secondary_shift=-0.05,
        kappa=0.5,
    )
    result = hj.fit(scene, target, init=start)
    assert result.fitted == FIT_NAMES and result.termination == "converged"
    for name in FIT_NAMES:
        np.testing.assert_allclose(
            getattr(result.params, name), getattr(truth, name), rtol=1e-8, err_msg=name
        )
        assert np.all(np.isfinite(result.std_error[name]))
    assert result.loss[0] > 1e-3 and result.rmse < 1e-10
    assert json.loads(json.dumps(result.to_json()))["params"]["primary_shift"] == pytest.approx(0.15)


def test_fit_refuses_what_it_cannot_do():
    scene = scheuermann_scene(size=8, strands=3, shadows="none")
    target = np.zeros((8, 8, 3))
    with pytest.raises(hj.FitError, match="unknown parameter 'ks' for a scheuermann scene"):
        hj.fit(scene, target, variables=("kd", "ks"))
    with pytest.raises(hj.FitError, match="grey value"):
        hj.fit(scene, target, variables=hj.FitVariables(("kd",), scalar=("primary_shift",)))
    kk = scene.replace(shading=hj.KajiyaKay(hj.ShadingParams()))
    with pytest.raises(hj.FitError, match="share a shading model"):
        hj.fit([scene, kk], [target, target])
    with pytest.raises(hj.FitError, match="from ScheuermannParams"):
        hj.fit(scene, target, init=hj.ShadingParams())


@pytest.mark.slow  # the CLI fit of Kajiya-Kay runs in make test (tests/cli/test_commands.py)
def test_fit_from_the_cli(tmp_path, capsys):
    import json

    from hairjax.cli import main

    scene_file = tmp_path / "s.toml"
    scene_file.write_text(
        '[hair]\nsource = "scalp"\nstrands = 20\npoints = 5\n'
        '[camera]\nwidth = 16\nheight = 12\n[shadows]\nmethod = "none"\n'
        '[shading]\nmodel = "scheuermann"\nprimary_shift = 0.2\n'
    )
    scene = hj.load_scene(scene_file)
    target = tmp_path / "t.exr"
    hj.write_image(target, np.asarray(hj.render(scene)))
    report = tmp_path / "fit.json"
    assert (
        main(
            [
                "fit",
                str(scene_file),
                "--target",
                str(target),
                "--fit",
                "primary_shift,secondary_color",
                "--json",
                str(report),
            ]
        )
        == 0
    )
    out = capsys.readouterr().out
    assert "primary_shift" in out and "fixed" in out  # every parameter listed, unfitted ones fixed
    # The target is float32 (EXR): recovery to float32 rounding.
    assert json.loads(report.read_text())["params"]["primary_shift"] == pytest.approx(0.2, rel=1e-4)
    assert main(["fit", str(scene_file), "--target", str(target), "--fit", "kd,shininess"]) == 2
    assert "unknown parameter 'shininess'" in capsys.readouterr().err
