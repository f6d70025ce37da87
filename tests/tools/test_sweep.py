"""`hairjax sweep` (hairjax/tools/_search.py run_sweep, _report.py): points, resuming, the report."""

import dataclasses
import json
import re

import numpy as np
import pytest
from helpers import small_furball_scene

import hairjax as hj
import hairjax.tools._search as search_mod
from hairjax import cli
from hairjax.tools import (
    SweepError,
    cheapest,
    knob_scene,
    load_points,
    run_sweep,
    summary_markdown,
    write_report,
)

KNOBS = {"bins": (1, "exact"), "maps": (2, 8)}


@pytest.fixture(scope="module")
def scene():
    return small_furball_scene(strands=60, size=24, maps=4, resolution=16)


def test_points_and_their_errors(scene, tmp_path, gl):
    points = run_sweep(scene, tmp_path, knobs=KNOBS, repeats=1, progress=False)
    assert {(p["path"], p["knob"], str(p["value"])) for p in points} == {
        (path, k, str(v)) for path in ("jax", "gl") for k, vs in KNOBS.items() for v in vs
    }
    for p in points:
        assert p["time_s"] > 0 and len(p["times"]) == 1
        assert np.isfinite(p["rmse"]) and p["max_abs"] >= p["rmse"] >= 0
        assert p["tau_rmse"] is not None and p["tau_max"] >= p["tau_rmse"]
    # The scene's opacity maps against the exact reference: a real, non-zero error.
    assert all(p["tau_max"] > 1e-3 for p in points)
    # Each path is measured against its own reference, rendered once and kept.
    assert (tmp_path / "reference_jax.npz").exists() and (tmp_path / "reference_gl.npz").exists()


def test_a_point_with_the_reference_settings_has_no_error(scene, tmp_path):
    exact = scene.replace(shadows=hj.Shadows("exact", resolution=16))
    points = run_sweep(
        exact, tmp_path, knobs={"bins": ("exact", 4)}, paths=("jax",), repeats=1, progress=False
    )
    by_value = {p["value"]: p for p in points}
    assert by_value["exact"]["rmse"] == 0.0 and by_value["exact"]["tau_max"] == 0.0
    assert by_value[4]["rmse"] > 0.0  # four bins do change the order


def test_resume_redoes_nothing_and_drops_a_cut_line(scene, tmp_path, monkeypatch):
    knobs = {"bins": (1, 4, "exact")}
    run_sweep(scene, tmp_path, knobs=knobs, paths=("jax",), repeats=1, progress=False)
    lines = (tmp_path / "points.jsonl").read_text().splitlines()
    # Simulate a kill while the last point was being written.
    (tmp_path / "points.jsonl").write_text("\n".join(lines[:2]) + "\n" + lines[2][:15])
    assert len(load_points(tmp_path)) == 2
    calls = []
    original = search_mod.measure
    monkeypatch.setattr(search_mod, "measure", lambda *a: calls.append(a[1]) or original(*a))
    points = run_sweep(scene, tmp_path, knobs=knobs, paths=("jax",), repeats=1, progress=False)
    assert len(calls) == 1 and len(points) == 3  # only the cut point, reference kept on disk
    assert sorted(str(p["value"]) for p in points) == ["1", "4", "exact"]


def test_interrupted_sweep_keeps_finished_points(scene, tmp_path, monkeypatch):
    original = search_mod.measure
    count = {"n": 0}

    def flaky(*args):
        count["n"] += 1
        if count["n"] == 2:  # one point, then Ctrl-C (the reference renders in _measure.py)
            raise KeyboardInterrupt
        return original(*args)

    monkeypatch.setattr(search_mod, "measure", flaky)
    with pytest.raises(KeyboardInterrupt):
        run_sweep(scene, tmp_path, knobs={"bins": (1, 4, 16)}, paths=("jax",), repeats=1, progress=False)
    assert [p["value"] for p in load_points(tmp_path)] == [1]
    monkeypatch.setattr(search_mod, "measure", original)
    points = run_sweep(scene, tmp_path, knobs={"bins": (1, 4, 16)}, paths=("jax",), repeats=1, progress=False)
    assert [p["value"] for p in points] == [1, 4, 16]


def test_folder_of_another_sweep_is_refused(scene, tmp_path):
    run_sweep(scene, tmp_path, knobs={"bins": (1,)}, paths=("jax",), repeats=1, progress=False)
    other = scene.replace(params=scene.params.__class__(kd=0.9, ks=0.1, shininess=5.0, kappa=1.0))
    with pytest.raises(SweepError, match="other settings"):
        run_sweep(other, tmp_path, knobs={"bins": (1,)}, paths=("jax",), repeats=1, progress=False)
    points = run_sweep(
        other, tmp_path, knobs={"bins": (4,)}, paths=("jax",), repeats=1, progress=False, restart=True
    )
    assert [p["value"] for p in points] == [4]


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(knobs={"gamma": (1,)}), "unknown knob"),
        (dict(paths=("vulkan",)), "unknown path"),
        (dict(repeats=0), r"^repeats must be a positive integer, got 0$"),
    ],
)
def test_bad_arguments(scene, tmp_path, kwargs, message, monkeypatch):
    def no_render(path):
        raise AssertionError("a renderer was made before the arguments were checked")

    monkeypatch.setattr(search_mod, "renderer", no_render)
    with pytest.raises(SweepError, match=message):
        run_sweep(scene, tmp_path, **{"knobs": {"bins": (1,)}, **kwargs})


def test_no_shadow_knobs_without_shadows(tmp_path):
    plain = small_furball_scene(strands=30, size=16, shadows="none")
    points = run_sweep(
        plain, tmp_path, knobs={"maps": (1, 2), "bins": (1,)}, paths=("jax",), repeats=1, progress=False
    )
    assert [(p["knob"], p["tau_rmse"]) for p in points] == [("bins", None)]


def test_width_knob_keeps_opacity_per_length(scene):
    wide, s = knob_scene(scene, "width", 2.0)
    assert s == 1
    np.testing.assert_allclose(wide.strands.width, 2 * scene.strands.width)
    np.testing.assert_allclose(wide.strands.alpha, scene.strands.alpha / 2)
    thin, _ = knob_scene(scene, "width", 0.5)
    np.testing.assert_allclose(thin.strands.alpha, np.minimum(2 * scene.strands.alpha, 1.0))
    assert knob_scene(scene, "supersampling", 3) == (scene, 3)


POINTS = [
    {"path": "jax", "knob": "maps", "value": 4, "time_s": 1.0, "rel_rmse": 0.02, "rmse": 0.02},
    {"path": "jax", "knob": "maps", "value": 16, "time_s": 2.0, "rel_rmse": 0.005, "rmse": 0.005},
    {"path": "jax", "knob": "bins", "value": 64, "time_s": 1.5, "rel_rmse": 0.009, "rmse": 0.009},
    {"path": "jax", "knob": "bins", "value": "exact", "time_s": 3.0, "rel_rmse": 5e-4, "rmse": 5e-4},
]
CONFIG = {
    "scene": "s",
    "size": [8, 8],
    "repeats": 1,
    "paths": ["jax"],
    "knobs": {"maps": [4, 16], "bins": [64, "exact"]},
    "reference": {"shadows": "exact", "ordering": "exact", "supersampling": 1},
}


def test_cheapest_settings():
    assert cheapest(POINTS, 1e-2, "jax")["value"] == 64  # 1.5 s beats maps = 16 at 2 s
    assert cheapest(POINTS, 1e-2, "jax", "maps")["value"] == 16
    assert cheapest(POINTS, 1e-3, "jax")["value"] == "exact"
    assert cheapest(POINTS, 1e-3, "jax", "maps") is None
    text = summary_markdown(POINTS, CONFIG)
    assert "| jax | bins = 64 (1.5 s) | 16 (2 s) | 64 (1.5 s) |" in text
    # 0.5 %: maps = 16 reaches it exactly (0.005), at 2 s before bins = exact's 3 s.
    after = text.split("## Cheapest settings reaching 0.5% relative RMSE")[1]
    assert after.split("\n\n")[1].splitlines()[2] == "| jax | maps = 16 (2 s) | 16 (2 s) | exact (3 s) |"
    assert "| jax | bins = exact (3 s) | not reached | exact (3 s) |" in text


def test_of_two_points_as_fast_the_lower_error_is_the_cheapest():
    """Such a point dominates the other (it is the front's), whatever their order."""
    slow = {"path": "jax", "knob": "maps", "value": 4, "time_s": 1.0, "rel_rmse": 0.008}
    good = {"path": "jax", "knob": "bins", "value": 16, "time_s": 1.0, "rel_rmse": 0.002}
    assert cheapest([slow, good], 1e-2, "jax") is good and cheapest([good, slow], 1e-2, "jax") is good


def test_report_files(tmp_path):
    files = write_report(tmp_path, POINTS, CONFIG)
    rows = files["csv"].read_text().splitlines()
    assert rows[0].startswith("path,knob,value,time_s") and len(rows) == 1 + len(POINTS)
    assert files["plot"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "## Cheapest settings reaching 1.0% relative RMSE" in files["summary"].read_text()


def test_cli_sweep(tmp_path, capsys):
    toml = tmp_path / "tiny.toml"
    toml.write_text(
        'name = "tiny"\n[hair]\nsource = "furball"\nstrands = 40\npoints = 5\n'
        "[camera]\nwidth = 16\nheight = 16\n"
        '[shadows]\nmethod = "opacity-maps"\nmaps = 4\nresolution = 16\n'
    )
    out = tmp_path / "sweep"
    args = [str(toml), "--out", str(out), "--paths", "jax", "--knobs", "bins", "--quick", "--repeats", "1"]
    assert cli.main(["sweep", *args]) == 0
    printed = capsys.readouterr().out
    assert "Cheapest settings reaching 1.0%" in printed and "wrote" in printed
    config = json.loads((out / "sweep.json").read_text())
    assert config["knobs"] == {"bins": [1, 16, "exact"]} and config["paths"] == ["jax"]
    assert len(load_points(out)) == 3 and (out / "pareto.png").exists()
    assert cli.main(["sweep", *args[:5], "--knobs", "gamma"]) == 2
    assert "unknown knob 'gamma'" in capsys.readouterr().err
    small = tmp_path / "small.exr"
    hj.write_image(small, np.ones((8, 8, 4)))
    assert cli.main(["sweep", *args, "--target", str(small), "--out", str(tmp_path / "t")]) == 2
    assert "the target is 8x8x4, the scene renders 16x16" in capsys.readouterr().err


def test_a_refused_setting_is_recorded_and_the_sweep_goes_on(scene, tmp_path, monkeypatch):
    original = search_mod.measure

    def refuse_four(run, variant, s, repeats):
        if variant.ordering == hj.Ordering("bins", 4):
            raise ValueError("4 bins exceed the test's budget")
        return original(run, variant, s, repeats)

    monkeypatch.setattr(search_mod, "measure", refuse_four)
    points = run_sweep(scene, tmp_path, knobs={"bins": (1, 4, 16)}, paths=("jax",), repeats=1, progress=False)
    assert [p["value"] for p in points] == [1, 4, 16]
    assert points[1]["skipped"] == "4 bins exceed the test's budget" and "rmse" not in points[1]
    config = json.loads((tmp_path / "sweep.json").read_text())
    files = write_report(tmp_path, points, config)
    assert "- jax, bins = 4: 4 bins exceed the test's budget" in files["summary"].read_text()
    assert len(files["csv"].read_text().splitlines()) == 3  # header and the two measured points


def test_a_given_target_is_every_point_s_reference(scene, tmp_path):
    """With `target`, each point's error is against that image (here the scene rendered
    with other shading parameters, as a physically based target differs from the model):
    no reference is rendered, and the error is the RMSE written out."""
    target = np.asarray(hj.render(scene, dataclasses.replace(scene.params, kd=scene.params.kd * 0.5)))
    points = run_sweep(
        scene,
        tmp_path,
        knobs={"bins": (1, "exact")},
        paths=("jax",),
        repeats=1,
        progress=False,
        target=target,
    )
    assert not (tmp_path / "reference_jax.npz").exists()
    for p in points:
        image = np.asarray(hj.render(knob_scene(scene, "bins", p["value"])[0]), np.float64)
        expected = np.sqrt(np.mean((image[..., :3] - target[..., :3]) ** 2))
        np.testing.assert_allclose(p["rmse"], expected, rtol=1e-9)  # one float64 sum, two orders
        assert p["rel_rmse"] == pytest.approx(p["rmse"] / target[..., :3].max()) and p["tau_rmse"] is None
    config = json.loads((tmp_path / "sweep.json").read_text())
    assert set(config["reference"]) == {"target"}
    text = summary_markdown(points, config)
    assert "## Cheapest settings within 10% of the best error" in text and "given target image" in text
    with pytest.raises(SweepError, match="the target is 8x8x4, the scene renders 24x24"):
        run_sweep(
            scene, tmp_path / "b", knobs={"bins": (1,)}, paths=("jax",), progress=False, target=target[:8, :8]
        )


def test_cheapest_within_ten_percent_of_the_best_error_against_a_target():
    config = {**CONFIG, "reference": {"target": "0123456789abcdef"}}
    points = [*POINTS, {"path": "jax", "knob": "maps", "value": 64, "time_s": 2.5, "rel_rmse": 5.4e-4}]
    text = summary_markdown(points, config)
    # Best 5e-4 (bins = exact, 3 s): within 10 %, maps = 64 (5.4e-4) at 2.5 s is cheaper.
    assert "| jax | maps = 64 (2.5 s) | 64 (2.5 s) | exact (3 s) |" in text
    assert "digest 0123456789abcdef" in text


# A damaged store, found when the sweep resumes: one line naming the file (and the line),
# exit 2, before any render. `content` replaces the file in a folder a sweep left.
DAMAGED = {
    "torn sweep.json": ("sweep.json", '{"scene": "tiny", "rep', r"sweep\.json: damaged settings file"),
    "sweep.json not an object": ("sweep.json", "[1, 2]\n", r"sweep\.json: damaged settings file"),
    "a number in points.jsonl": ("points.jsonl", '3\n{"path": "jax"', r"points\.jsonl:1: not a JSON object"),
    "a torn line before the last": (
        "points.jsonl",
        '{"path": "jax", "kno\n{"path": "jax", "knob": "bins", "value": 1}\n',
        r"points\.jsonl:1: not a JSON line",
    ),
    "a point without its keys": (
        "points.jsonl",
        '{"path": "jax"}\n',
        r"points\.jsonl:1: a point without knob",
    ),
    "a list in joint.jsonl": ("joint.jsonl", '[1]\n{"path": "jax"}\n', r"joint\.jsonl:1: not a JSON object"),
    "torn joint.json": ("joint.json", "{", r"joint\.json: damaged settings file"),
}


@pytest.mark.parametrize("case", DAMAGED)
def test_a_damaged_store_is_named_on_resume(case, tmp_path, monkeypatch, capsys):
    name, content, message = DAMAGED[case]
    joint = name.startswith("joint")
    (tmp_path / name).write_text(content)
    if name.endswith(".jsonl"):  # settings taken as matching, so the points are read
        monkeypatch.setattr("hairjax.tools._store.Store.check_config", lambda *a, **k: None)

    def no_render(*args):
        raise AssertionError("a renderer was made before the store was checked")

    monkeypatch.setattr("hairjax.tools._measure.renderer", no_render)
    monkeypatch.setattr(search_mod, "renderer", no_render)
    toml = tmp_path / "tiny.toml"
    toml.write_text('[hair]\nsource = "furball"\nstrands = 20\npoints = 4\n[camera]\nwidth = 8\nheight = 8\n')
    argv = ["sweep", str(toml), "--out", str(tmp_path), "--paths", "jax", "--knobs", "bins", "--quick"]
    assert cli.main([*argv, *(["--joint"] if joint else [])]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert err.startswith(f"hairjax: error: {tmp_path / name}"), err
    assert re.search(message, err), err
