"""The command line: render, info, errors, atomic output."""

import os

import jax.numpy as jnp
import numpy as np
import pytest
from helpers import DATA

import hairjax as hj
from hairjax.cli import main

SMALL_SCENE = """
[hair]
source = "furball"
strands = 60
points = 5
[camera]
width = 40
height = 30
[shadows]
maps = 4
resolution = 32
"""


@pytest.fixture
def scene_file(tmp_path):
    path = tmp_path / "small.toml"
    path.write_text(SMALL_SCENE)
    return path


def test_render_writes_exr_and_png(scene_file, tmp_path, capsys):
    exr, png = tmp_path / "out" / "a.exr", tmp_path / "out" / "a.png"
    assert main(["render", str(scene_file), "-o", str(exr), "--png", str(png), "--profile"]) == 0
    out = capsys.readouterr().out
    assert "shading" in out and "geometry" in out
    img = hj.read_image(exr)
    assert img.shape == (30, 40, 4)
    expected = np.asarray(hj.render(hj.load_scene(scene_file)), dtype=np.float32)
    np.testing.assert_allclose(img, expected, atol=1e-6)  # float32 EXR of a float64 render
    view = hj.read_image(png)
    assert view.shape == (30, 40, 3)
    # 8-bit sRGB rounding is ≤ ½ step; in linear that is at most the steepest slope of the
    # sRGB decode (2.4/1.055 at 1.0) times 0.5/255.
    np.testing.assert_allclose(view, np.clip(expected[..., :3], 0, 1), atol=2.4 / 1.055 * 0.5 / 255)
    assert sorted(os.listdir(exr.parent)) == ["a.exr", "a.json", "a.png"]  # no temporary files left
    umask = os.umask(0)
    os.umask(umask)
    assert exr.stat().st_mode & 0o777 == 0o666 & ~umask  # as a plain write, not mkstemp's 0600


def test_render_sidecar_records_the_scene_as_resolved(scene_file, tmp_path):
    import json

    import hairjax

    exr = tmp_path / "b.exr"
    argv = ["render", str(scene_file), "-o", str(exr), "--set", "shading.ks=0.125", "--size", "20", "-q"]
    assert main(argv) == 0
    record = json.loads((tmp_path / "b.json").read_text())
    assert record["overrides"] == {"shading.ks": 0.125, "camera.width": 20, "camera.height": 15}
    np.testing.assert_allclose(record["shading"]["params"]["ks"], 0.125)
    assert record["scene"]["camera"]["width"] == 20 and record["scene"]["camera"]["height"] == 15
    assert record["scene"]["shadows"] == {"type": "OpacityMaps", "maps": 4, "resolution": 32} | {
        k: v for k, v in record["scene"]["shadows"].items() if k not in ("type", "maps", "resolution")
    }
    assert record["scene"]["strands"]["points"]["shape"] == [60 * 5, 3]  # summarised, not listed
    assert record["versions"]["hairjax"] == hairjax.__version__ and "jax" in record["versions"]
    assert set(record["timings_s"]) >= {"shading"} and all(t >= 0 for t in record["timings_s"].values())
    assert hj.read_image(exr).shape == (15, 20, 4)
    assert main(["render", str(scene_file), "-o", str(tmp_path / "c.exr"), "--no-sidecar", "-q"]) == 0
    assert not (tmp_path / "c.json").exists()


def test_quiet_prints_nothing_on_success(scene_file, tmp_path, capsys):
    assert main(["render", str(scene_file), "-o", str(tmp_path / "q.exr"), "-q"]) == 0
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err == ""


def test_view_tone_maps_with_exposure(tmp_path):
    image = np.full((4, 6, 4), 0.25, dtype=np.float32)
    hj.write_image(tmp_path / "i.exr", image)
    assert main(["view", str(tmp_path / "i.exr"), "--exposure", "1", "-q"]) == 0
    view = hj.read_image(tmp_path / "i.png")  # decoded back to linear
    # One stop doubles 0.25 to 0.5; 8-bit sRGB rounding is ≤ ½ step, in linear at most the
    # decode's steepest slope (2.4/1.055, at 1.0) times 0.5/255.
    np.testing.assert_allclose(view, 0.5, atol=2.4 / 1.055 * 0.5 / 255)


def test_failed_write_leaves_no_file(scene_file, tmp_path, capsys):
    bad = tmp_path / "image.bmpx"
    assert main(["render", str(scene_file), "-o", str(bad)]) == 2
    assert "unsupported extension" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == [scene_file]


def test_bad_scene_is_a_clear_error(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text('[hair]\nsource = "furball"\nwidth = -1\n')
    assert main(["render", str(path), "-o", str(tmp_path / "x.exr")]) == 2
    err = capsys.readouterr().err
    assert "hair.width" in err and "bad.toml" in err
    assert not (tmp_path / "x.exr").exists()


@pytest.mark.skipif(not DATA.is_dir(), reason="shared/data is not beside the checkout")
def test_info_prints_counts(capsys):
    assert main(["info", str(DATA / "tressfx" / "ponytail_tail.tfx")]) == 0
    out = capsys.readouterr().out
    assert "255" in out and "4080" in out.replace(",", "")


def test_info_on_malformed_file(tmp_path, capsys):
    bad = tmp_path / "bad.hair"
    bad.write_bytes(b"NOPE" + bytes(200))
    assert main(["info", str(bad)]) == 2
    assert "bad.hair" in capsys.readouterr().err


def test_fit_from_the_cli(scene_file, tmp_path, capsys):
    import json

    scene = hj.load_scene(scene_file)
    true = hj.ShadingParams(kd=(0.3, 0.5, 0.2), ks=0.4, shininess=25.0, kappa=2.5)
    target = tmp_path / "t.exr"
    hj.write_image(target, np.asarray(hj.render(scene, true)))
    out, report, plot = tmp_path / "fitted.exr", tmp_path / "fit.json", tmp_path / "fit.png"
    argv = ["fit", str(scene_file), "--target", str(target), "--json", str(report), "--out", str(out)]
    assert main([*argv, "--plot", str(plot)]) == 0
    captured = capsys.readouterr()
    assert "loss" in captured.err  # the progress lines
    assert "fitted" in captured.out and "std. error" in captured.out
    data = json.loads(report.read_text())
    for key in ("params", "initial", "steps", "time_s", "loss", "rmse", "termination"):
        assert key in data
    # The target is float32 (EXR), so recovery is to float32 rounding, not 1e-12.
    np.testing.assert_allclose(data["params"]["kappa"], 2.5, rtol=1e-3)
    assert out.exists()
    figure = hj.read_image(plot)  # target | fit | residual, side by side
    assert figure.shape[1] > 2 * figure.shape[0]


def test_fit_that_stops_without_converging_exits_3(scene_file, tmp_path, monkeypatch, capsys):
    """The exit code follows the fit's termination (a real fit at its step limit is
    tests/fit's; here the fit is replaced by its result, so no compilation is needed)."""
    import dataclasses

    from hairjax._fit import FitResult

    params = hj.load_scene(scene_file).params
    fields = dict(params=params, initial=params, fitted=("kd",), loss=[1.0], steps=1, time_s=0.1)
    fields |= dict(geometry_s=0.1, std_error={"kd": None}, undetermined=(), rmse=0.5)
    stopped = FitResult(**fields, termination="stopped: reached max_steps = 1")
    monkeypatch.setattr("hairjax._fit.fit", lambda *args, **kwargs: stopped)
    target = tmp_path / "t.exr"
    hj.write_image(target, np.zeros((30, 40, 4)))
    argv = ["fit", str(scene_file), "--target", str(target), "--max-steps", "1", "-q"]
    assert main(argv) == 3
    assert "stopped: reached max_steps = 1" in capsys.readouterr().out
    converged = dataclasses.replace(stopped, termination="converged")
    monkeypatch.setattr("hairjax._fit.fit", lambda *args, **kwargs: converged)
    assert main(argv) == 0


def test_fit_takes_the_light_names(scene_file, tmp_path, monkeypatch, capsys):
    """--fit accepts light_direction and light_color beside the model's names and passes
    them on; the table and the JSON report the light (the fit is replaced by its result,
    as above: no compilation)."""
    import json

    from hairjax._fit import FitResult

    params = hj.load_scene(scene_file).params
    fitted = hj.LightParams(direction=(0.1, -0.9, -0.4), color=(1.0, 0.8, 0.6))
    errors = {"light_direction": 1e-3, "light_color": np.full(3, 1e-3), "ks": np.full(3, 1e-3)}
    names = ("light_direction", "light_color", "ks")
    fields = dict(params=params, initial=params, fitted=names, loss=[1.0, 0.5], steps=1, time_s=0.1)
    fields |= dict(geometry_s=0.1, std_error=errors, undetermined=(), rmse=0.5, termination="converged")
    result = FitResult(
        **fields, light=fitted, initial_light=hj.LightParams(direction=(-1, -1, -1), color=1.0)
    )
    calls = []
    monkeypatch.setattr("hairjax._fit.fit", lambda *args, **kwargs: calls.append(kwargs) or result)
    target, report = tmp_path / "t.exr", tmp_path / "fit.json"
    hj.write_image(target, np.zeros((30, 40, 4)))
    argv = ["fit", str(scene_file), "--target", str(target), "--json", str(report), "-q"]
    assert main([*argv, "--fit", ",".join(names)]) == 0
    assert calls[0]["variables"].names == names
    rows = {line.split()[0]: line for line in capsys.readouterr().out.splitlines() if line}
    assert "0.8" in rows["light_color"] and "-0.9" in rows["light_direction"] and "fixed" in rows["kd"]
    assert json.loads(report.read_text())["light"]["color"] == [1.0, 0.8, 0.6]
    assert main([*argv, "--fit", "light_gloss"]) == 2
    assert "light_direction, light_color" in capsys.readouterr().err


def test_fit_takes_alpha(scene_file, tmp_path, monkeypatch, capsys):
    """--fit accepts the strands' opacity; the table shows its start and fitted value, and
    --out renders at the fitted opacity (the fit is replaced by its result)."""
    from hairjax._fit import FitResult

    params = hj.load_scene(scene_file).params
    fields = dict(params=params, initial=params, fitted=("kd", "alpha"), loss=[1.0], steps=1, time_s=0.1)
    fields |= dict(geometry_s=0.1, std_error={"kd": None, "alpha": 0.01}, undetermined=(), rmse=0.5)
    result = FitResult(**fields, termination="converged", alpha=0.25, initial_alpha=0.8)
    calls = []
    monkeypatch.setattr("hairjax._fit.fit", lambda *args, **kwargs: calls.append(kwargs) or result)
    target, out = tmp_path / "t.exr", tmp_path / "fitted.exr"
    hj.write_image(target, np.zeros((30, 40, 4)))
    argv = ["fit", str(scene_file), "--target", str(target), "--fit", "kd,alpha", "--out", str(out), "-q"]
    assert main(argv) == 0
    assert calls[0]["variables"].names == ("kd", "alpha")
    row = next(line for line in capsys.readouterr().out.splitlines() if line.startswith("alpha"))
    assert row.split()[1:4] == ["0.8", "0.25", "0.01"]
    scene = hj.load_scene(scene_file)
    expected = hj.render(scene, params, jnp.full(scene.strands.num_strands, 0.25))
    np.testing.assert_allclose(hj.read_image(out), expected, atol=1e-6)  # EXR float32


def test_fit_reports_the_held_out_rmse(scene_file, tmp_path, monkeypatch, capsys):
    """--holdout targets go to the fit with their --holdout-scene (or the first scene),
    read before the fit; the held-out RMSE is printed and in the JSON (the fit is replaced
    by its result: tests/fit/test_holdout.py computes it)."""
    import dataclasses
    import json

    from hairjax._fit import FitResult

    params = hj.load_scene(scene_file).params
    fields = dict(params=params, initial=params, fitted=("kd",), loss=[1.0], steps=1, time_s=0.1)
    fields |= dict(geometry_s=0.1, std_error={"kd": None}, undetermined=(), rmse=0.5)
    result = FitResult(**fields, termination="converged", holdout_rmse=0.0123)
    calls = []  # the FitTargets each fit is given
    monkeypatch.setattr("hairjax._fit.fit", lambda scenes, targets, *a, **kw: calls.append(targets) or result)
    other = tmp_path / "side.toml"
    other.write_text(SMALL_SCENE + "[light]\ndirection = [0.6, -0.7, -0.3]\n")
    target, held, report = tmp_path / "t.exr", tmp_path / "h.exr", tmp_path / "fit.json"
    hj.write_image(target, np.zeros((30, 40, 4)))
    hj.write_image(held, np.full((30, 40, 4), 0.5))
    argv = ["fit", str(scene_file), "--target", str(target), "--json", str(report), "-q"]
    assert main([*argv, "--holdout", str(held), "--holdout-scene", str(other), "--holdout", str(held)]) == 0
    scenes, targets = calls[0].holdout
    first_light = hj.load_scene(scene_file).light.direction
    assert [s.light.direction for s in scenes] == [(0.6, -0.7, -0.3), first_light]
    assert len(targets) == 2 and np.all(np.asarray(targets[0])[..., :3] == 0.5)
    assert "held-out RMSE 0.0123 (2 target(s) the fit did not see)" in capsys.readouterr().out
    assert json.loads(report.read_text())["holdout_rmse"] == 0.0123
    # Without --holdout, no held-out line and None in the JSON.
    monkeypatch.setattr("hairjax._fit.fit", lambda *a, **k: dataclasses.replace(result, holdout_rmse=None))
    assert main(argv) == 0
    assert "held-out" not in capsys.readouterr().out
    assert json.loads(report.read_text())["holdout_rmse"] is None
    # A --holdout-scene without its --holdout, or an unreadable held-out target: one line, before work.
    assert main([*argv, "--holdout-scene", str(other)]) == 2
    assert "each --holdout-scene goes with one --holdout" in capsys.readouterr().err
    assert main([*argv, "--holdout", str(tmp_path / "missing.exr")]) == 2
    assert "missing.exr" in capsys.readouterr().err


@pytest.mark.parametrize(
    "args, message",
    [
        (["--fit", "kd,gloss"], "unknown parameter 'gloss'"),
        (["--target", "missing.exr"], "no such file"),
    ],
)
def test_fit_errors_before_work(scene_file, tmp_path, capsys, args, message):
    target = tmp_path / "t.exr"
    hj.write_image(target, np.zeros((30, 40, 4)))
    argv = ["fit", str(scene_file), "--target", str(target), *args]
    if args[0] == "--target":
        argv = ["fit", str(scene_file), "--target", str(tmp_path / args[1])]
    assert main(argv) == 2
    assert message in capsys.readouterr().err


def test_fit_target_size_mismatch(scene_file, tmp_path, capsys):
    target = tmp_path / "small.exr"
    hj.write_image(target, np.zeros((10, 10, 4)))
    assert main(["fit", str(scene_file), "--target", str(target)]) == 2
    assert "renders 40x30" in capsys.readouterr().err


@pytest.mark.skipif(not DATA.is_dir(), reason="shared/data is not beside the checkout")
def test_render_a_bare_hair_file_frames_it(tmp_path, capsys):
    """`hairjax render FILE.hair` frames the asset (the default camera shows it black) and
    takes --set and --size like a scene file."""
    out = tmp_path / "bangs.exr"
    argv = ["render", str(DATA / "hair" / "Bangs_100.hair"), "--size", "64", "-o", str(out), "-q"]
    assert main([*argv, "--set", "shading.ks=0.125"]) == 0
    image = hj.read_image(out)
    assert image.shape == (64, 64, 4)
    # A framed asset's acceptance threshold: its hair covers at least 5 % of the pixels.
    assert (image[..., 3] > 0).mean() >= 0.05
    import json

    record = json.loads((tmp_path / "bangs.json").read_text())
    np.testing.assert_allclose(record["shading"]["params"]["ks"], 0.125)
    assert "warning" not in capsys.readouterr().err


def test_a_camera_that_misses_the_hair_warns_once(scene_file, tmp_path, capsys):
    out = tmp_path / "away.exr"
    argv = ["render", str(scene_file), "-o", str(out), "-q", "--set", "camera.target=[0, 0, 10]"]
    assert main(argv) == 0
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("hairjax: warning: the hair covers no pixel")
    assert "bounding box" in lines[0] and "eye" in lines[0]


def test_fit_save_scene_writes_the_fitted_parameters(scene_file, tmp_path, monkeypatch):
    """--save-scene: a scene file holding the fitted model parameters, light and opacity,
    which renders what --out rendered where the fit fitted the model's parameters alone
    (the fit is replaced by its result: no compilation)."""
    from hairjax._fit import FitResult

    scene = hj.load_scene(scene_file)
    fitted = hj.ShadingParams(kd=(0.3, 0.5, 0.2), ks=0.4, shininess=25.0, kappa=2.5)
    fields = dict(params=fitted, initial=scene.params, fitted=("kd",), loss=[1.0], steps=1, time_s=0.1)
    fields |= dict(geometry_s=0.1, std_error={"kd": None}, undetermined=(), rmse=0.5, termination="converged")
    result = FitResult(**fields)
    monkeypatch.setattr("hairjax._fit.fit", lambda *args, **kwargs: result)
    target, out, saved = tmp_path / "t.exr", tmp_path / "fitted.exr", tmp_path / "fitted.toml"
    hj.write_image(target, np.zeros((30, 40, 4)))
    argv = ["fit", str(scene_file), "--target", str(target), "-q", "--out", str(out)]
    assert main([*argv, "--save-scene", str(saved)]) == 0
    assert "kd = [0.3, 0.5, 0.2]" in saved.read_text() and "shininess = 25.0" in saved.read_text()
    again = hj.load_scene(saved)
    assert np.array_equal(np.asarray(again.params.kd), np.asarray(fitted.kd))
    np.testing.assert_array_equal(hj.read_image(out), np.asarray(hj.render(again), dtype=np.float32))
    light = hj.LightParams(direction=(0.1, -0.9, -0.4), color=(1.0, 0.8, 0.6))
    monkeypatch.setattr(
        "hairjax._fit.fit",
        lambda *a, **k: FitResult(**fields, light=light, initial_light=light, alpha=0.25, initial_alpha=0.5),
    )
    assert main([*argv, "--save-scene", str(saved)]) == 0
    again = hj.load_scene(saved)
    assert again.light.direction == (0.1, -0.9, -0.4) and again.light.color == (1.0, 0.8, 0.6)
    assert np.all(again.strands.alpha == 0.25)
    assert main([*argv, "--save-scene", str(tmp_path / "fitted.json")]) == 2  # a scene file is .toml
