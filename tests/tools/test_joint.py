"""The joint search (hairjax/tools/_knob_space.py, _pareto.py, _search.py run_joint, _report.py):
its space, its algorithm on hand-made tables, the front it finds against the full grid of
a small space, resuming, the report and the command line."""

import json
import math
import random

import numpy as np
import pytest
from helpers import small_furball_scene

import hairjax.tools._search as search_mod
from hairjax import cli
from hairjax._geometry._shadows import shadow_method_names
from hairjax.tools import (
    QUICK_JOINT_KNOBS,
    KnobSpace,
    SearchConfig,
    SweepError,
    knob_space,
    load_joint,
    pareto_front,
    pareto_search,
    run_joint,
    write_report,
)
from hairjax.tools._knob_space import setting_key
from hairjax.tools._pareto import near_front

SHADOWS = {"none": (), "exact": ("map_resolution",), "opacity-maps": ("maps", "map_resolution")}


def test_the_space_s_steps_and_grid():
    knobs = {
        "shadows": ("none", "exact", "opacity-maps"),
        "maps": (4, 16),
        "map_resolution": (16, 32),
        "bins": (1, "exact"),
    }
    space = KnobSpace(knobs, SHADOWS, "opacity-maps")
    start = space.start()
    assert start == {"shadows": "none", "bins": 1}
    assert space.steps(start) == [
        {"shadows": "none", "bins": "exact"},
        {"shadows": "exact", "map_resolution": 16, "bins": 1},
        {"shadows": "opacity-maps", "maps": 4, "map_resolution": 16, "bins": 1},
    ]
    # Switching keeps the knobs both methods have and starts the others at their first value.
    top = {"shadows": "exact", "map_resolution": 32, "bins": "exact"}
    assert space.steps(top) == [
        {"shadows": "none", "bins": "exact"},
        {"shadows": "opacity-maps", "maps": 4, "map_resolution": 32, "bins": "exact"},
    ]
    grid = list(space.grid())
    assert len(grid) == space.size() == 2 + 2 * 2 + 2 * 2 * 2
    assert len({setting_key(s) for s in grid}) == len(grid)
    assert KnobSpace.from_json(json.loads(json.dumps(space.to_json()))) == space


def test_the_space_of_a_scene():
    scene = small_furball_scene(strands=10, size=8, maps=4, resolution=16)
    knobs = {"maps": (4, 16), "layers": (2, 4), "bins": (1, 4)}
    space = knob_space(scene, knobs)
    assert dict(space.knobs) == {"maps": (4, 16), "bins": (1, 4)}  # no method of the space has layers
    assert space.start() == {"maps": 4, "bins": 1}  # the scene's method throughout
    unshadowed = knob_space(
        small_furball_scene(strands=10, size=8, shadows="none"), {**knobs, "shadows": ("none",)}
    )
    assert dict(unshadowed.knobs) == {"bins": (1, 4)}


def _brute_near_front(points, tol):
    def dominates(q, p):
        return (
            q["time_s"] * (1 + tol) <= p["time_s"]
            and q["rel_rmse"] <= p["rel_rmse"]
            and (q["time_s"] < p["time_s"] or q["rel_rmse"] < p["rel_rmse"])
        )

    return [p for p in points if not any(dominates(q, p) for q in points)]


@pytest.mark.parametrize("tol", [0.0, 0.1])
def test_near_front_is_the_definition(tol):
    rng = random.Random(0)
    # Few distinct values, so that ties in time, in error and in both are common.
    points = [
        {"time_s": rng.choice([1.0, 1.05, 1.2, 2.0]), "rel_rmse": rng.choice([0.1, 0.2, 0.3])}
        for _ in range(40)
    ]
    points.append({"time_s": 0.5, "skipped": "refused"})
    expected = _brute_near_front([p for p in points if "skipped" not in p], tol)
    assert [id(p) for p in near_front(points, tol)] == [id(p) for p in expected]


def test_pareto_front_by_hand():
    a, b, c, d, e = (
        {"time_s": 1.0, "rel_rmse": 0.3},
        {"time_s": 2.0, "rel_rmse": 0.1},
        {"time_s": 2.0, "rel_rmse": 0.2},  # as fast as b, worse
        {"time_s": 3.0, "rel_rmse": 0.1},  # as good as b, slower
        {"time_s": 4.0, "rel_rmse": 0.0},
    )
    assert pareto_front([e, d, c, b, a]) == [a, b, e]
    assert pareto_front([a, dict(a)]) == [a, a]  # two equal points are both on it


# A two-knob space by hand: a = 1 raises the error before a = 2 lowers it, so the step up
# is followed by the next one (lookahead); b = 1 at a = 0 is 3.2 s, within 10 % of
# a = 2's 3 s, so only the time tolerance expands it.
TABLE = {
    (0, 0): (1.0, 0.10),
    (1, 0): (2.0, 0.11),
    (2, 0): (3.0, 0.02),
    (0, 1): (3.2, 0.05),
    (1, 1): (5.0, 0.04),
    (2, 1): (6.0, 0.001),
}
HAND = KnobSpace({"a": (0, 1, 2), "b": (0, 1)}, {"m": ()}, "m")


def _table_evaluate(calls):
    def evaluate(setting):
        calls.append((setting["a"], setting["b"]))
        time_s, error = TABLE[calls[-1]]
        return {"settings": setting, "time_s": time_s, "rel_rmse": error}

    return evaluate


@pytest.mark.parametrize(
    "config, order",
    [
        # Greedy: from (0, 0) the steps (1, 0), then (2, 0) (lookahead), and (0, 1); (2, 0)
        # has the best error reduction per second (0.08 / 2 s), then (2, 1). Closing the
        # front: (0, 1) is dominated by (2, 0), (1, 0) by (0, 0); all front points expanded.
        (SearchConfig(stop_at=1e-4, time_tolerance=0.0), [(0, 0), (1, 0), (2, 0), (0, 1), (2, 1)]),
        # With a 10 % tolerance (0, 1) is near the front and is expanded: (1, 1).
        (SearchConfig(stop_at=1e-4), [(0, 0), (1, 0), (2, 0), (0, 1), (2, 1), (1, 1)]),
        # The target reached at (2, 1): nothing below it is searched, and above it every
        # front point is expanded already.
        (SearchConfig(stop_at=0.01, time_tolerance=0.0), [(0, 0), (1, 0), (2, 0), (0, 1), (2, 1)]),
        (SearchConfig(stop_at=1e-4, budget=3), [(0, 0), (1, 0), (2, 0)]),
        # 1 s + 2 s spent (each point's time_s, as it has no wall_s): nothing after.
        (SearchConfig(stop_at=1e-4, budget_s=3.0), [(0, 0), (1, 0)]),
    ],
)
def test_the_search_on_a_table_by_hand(config, order):
    calls = []
    points = pareto_search(HAND, _table_evaluate(calls), config)
    assert calls == order and [(p["settings"]["a"], p["settings"]["b"]) for p in points] == order


def test_the_target_stops_the_descent():
    calls = []
    pareto_search(HAND, _table_evaluate(calls), SearchConfig(stop_at=0.05, time_tolerance=0.0))
    # (2, 0) at 2 % reaches it: (2, 1) is never evaluated; (0, 0), the only front point
    # above it, is expanded already.
    assert calls == [(0, 0), (1, 0), (2, 0), (0, 1)]


# a = 1 is 1 % faster than a = 0 and barely better: within timing noise, not a free step.
NOISY = {
    (0, 0): (1.0, 0.1),
    (1, 0): (0.99, 0.099),
    (0, 1): (1.5, 0.05),
    (1, 1): (1.6, 0.04),
    (0, 2): (2.0, 1e-4),
    (1, 2): (2.1, 5e-5),
}


@pytest.mark.parametrize(
    "tolerance, order",
    [
        # Charged no time, a = 1 has an infinite gain per second and the descent takes it,
        # then b up twice; closing the front then finds (0, 2).
        (0.0, [(0, 0), (1, 0), (0, 1), (1, 1), (1, 2), (0, 2)]),
        # Charged 10 % of 1 s: 0.001 / 0.1 s loses to b = 1's 0.05 / 0.5 s, and the descent
        # reaches the target at (0, 2) with one expansion fewer on its way.
        (0.1, [(0, 0), (1, 0), (0, 1), (1, 1), (0, 2), (1, 2)]),
    ],
)
def test_a_step_faster_by_noise_alone_is_not_free(tolerance, order):
    space = KnobSpace({"a": (0, 1), "b": (0, 1, 2)}, {"m": ()}, "m")
    calls = []

    def evaluate(setting):
        calls.append((setting["a"], setting["b"]))
        time_s, error = NOISY[calls[-1]]
        return {"settings": setting, "time_s": time_s, "rel_rmse": error}

    pareto_search(space, evaluate, SearchConfig(stop_at=1e-3, time_tolerance=tolerance))
    assert calls == order


def _model_cost(s):
    """Seconds charged to a setting (a cost model: fixed, so the check is exact): more
    samples, maps, raster texels, bins and wider ribbons all cost more."""
    method = {
        "none": 0.0,
        "opacity-maps": 0.05 * s.get("maps", 0),
        "deep": 0.1 * s.get("layers", 0),
        "exact": 1.7,
    }[s["shadows"]]
    raster = (s.get("map_resolution", 16) / 16) ** 2
    order = 0.35 if s["bins"] == "exact" else 0.1 * math.log2(1 + s["bins"])
    return s.get("supersampling", 1) ** 2 * (0.5 + s.get("width", 1.0)) * (1 + method * raster + order)


SMALL = {
    "shadows": ("none", "exact", "opacity-maps"),
    "maps": (1, 2, 4, 8),
    "map_resolution": (16, 32),
    "bins": (1, 4, "exact"),
    "width": (0.5, 1.0),
    "supersampling": (1, 2),
}


@pytest.fixture(scope="module")
def grid(tmp_path_factory, gl_context):
    """Every setting of SMALL rendered with GL on a small fur ball (real errors), each
    charged `_model_cost` seconds."""
    scene = small_furball_scene(strands=80, size=24, maps=8, resolution=16)
    out = tmp_path_factory.mktemp("grid")
    points = run_joint(scene, out, knobs=SMALL, paths=("gl",), search=None, cost=_model_cost)
    return scene, out, points


# With no tolerance the lookahead is what finds the whole front here (without it, two
# points are missed); the default tolerance finds it with more points evaluated.
@pytest.mark.parametrize("tolerance", [0.0, 0.1])
def test_the_search_misses_no_point_of_the_grid_s_front(grid, tolerance):
    scene, _, points = grid
    space = knob_space(scene, SMALL)
    assert len(points) == space.size() == 132
    by_key = {setting_key(p["settings"]): p for p in points}
    config = SearchConfig(time_tolerance=tolerance)
    found = pareto_search(space, lambda s: by_key[setting_key(s)], config)
    keys = [setting_key(p["settings"]) for p in found]
    assert len(set(keys)) == len(keys)  # never a setting twice
    front = {setting_key(p["settings"]) for p in pareto_front(points) if p["rel_rmse"] > config.stop_at}
    assert len(front) >= 10  # a front worth searching (the check means little on two points)
    assert front <= {setting_key(p["settings"]) for p in pareto_front(found)}
    # 68 and 80 of the 132 here (40 % and 44 % of the grid's seconds): this small grid is
    # mostly front and its neighbours; the fraction falls as the space grows.
    assert len(found) < 0.7 * len(points)


def test_a_search_in_a_finished_folder_renders_nothing(grid, tmp_path, monkeypatch):
    scene, out, points = grid
    by_key = {setting_key(p["settings"]): p for p in points}
    expected = pareto_search(knob_space(scene, SMALL), lambda s: by_key[setting_key(s)])
    monkeypatch.setattr(search_mod, "measure", lambda *a: pytest.fail("rendered a stored point"))
    calls = []
    found = run_joint(
        scene, out, knobs=SMALL, paths=("gl",), cost=_model_cost, progress=lambda *a: calls.append(a)
    )
    assert found == expected
    assert calls == [(0, len(points), f"gl: resuming, {len(points)} points already measured")]


def test_an_interrupted_search_continues(tmp_path, monkeypatch, gl):
    scene = small_furball_scene(strands=40, size=16, maps=4, resolution=16)
    knobs = {"shadows": ("none", "opacity-maps"), "maps": (2, 4), "bins": (1, "exact")}
    original = search_mod.measure
    renders = []

    def interrupt_after_three(*args):
        renders.append(args[1])
        if len(renders) == 4:  # the reference, three points, then Ctrl-C
            raise KeyboardInterrupt
        return original(*args)

    monkeypatch.setattr(search_mod, "measure", interrupt_after_three)
    with pytest.raises(KeyboardInterrupt):
        run_joint(scene, tmp_path, knobs=knobs, paths=("gl",), cost=_model_cost)
    assert len(load_joint(tmp_path)) == 3
    (tmp_path / "joint.jsonl").write_text((tmp_path / "joint.jsonl").read_text() + '{"path": "gl", "sett')
    monkeypatch.setattr(search_mod, "measure", lambda *a: renders.append(a[1]) or original(*a))
    renders.clear()
    resumed = run_joint(scene, tmp_path, knobs=knobs, paths=("gl",), cost=_model_cost)
    assert len(renders) == len(resumed) - 3  # only the points not yet measured (the reference is kept)
    fresh = run_joint(scene, tmp_path / "fresh", knobs=knobs, paths=("gl",), cost=_model_cost)
    assert [p["settings"] for p in resumed] == [p["settings"] for p in fresh]


def test_a_small_search_with_real_renders(tmp_path, gl):
    """End to end, both paths, measured times: the points, the report, the progress. (The
    scene and knobs of tests/tools/test_sweep.py, whose JAX programs the cache then holds.)"""
    scene = small_furball_scene(strands=60, size=24, maps=4, resolution=16)
    calls = []
    points = run_joint(
        scene,
        tmp_path,
        knobs={"bins": (1, "exact"), "maps": (2, 8)},
        repeats=1,
        search=SearchConfig(budget=3),
        progress=lambda *a: calls.append(a),
    )
    assert [p["path"] for p in points] == ["jax"] * 3 + ["gl"] * 3
    for p in points:
        peak = float(np.load(tmp_path / f"reference_{p['path']}.npz")["peak"])
        assert p["time_s"] > 0 and len(p["times"]) == 1 and p["rel_rmse"] == pytest.approx(p["rmse"] / peak)
        assert p["wall_s"] > p["time_s"]  # the warm-up and the timed render
    assert calls[0] == (0, 1, "jax reference") and calls[1][:2] == (1, 3)
    assert calls[1][2].startswith("jax bins=1 maps=2: ")
    config = json.loads((tmp_path / "joint.json").read_text())
    files = write_report(tmp_path, points, config)
    assert files["pareto"].read_text().splitlines()[0] == "path,bins,maps,time_s,rel_rmse,rmse,max_abs"
    assert files["plot"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "the budget (3 points per path) ran out" in files["summary"].read_text()


REPORT_SPACE = KnobSpace(
    {"shadows": ("none", "opacity-maps"), "maps": (4, 16), "supersampling": (1, 2)},
    {"none": (), "opacity-maps": ("maps",)},
    "opacity-maps",
)


def _point(path, time_s, error, shadows, supersampling, maps=None):
    settings = {
        "shadows": shadows,
        **({} if maps is None else {"maps": maps}),
        "supersampling": supersampling,
    }
    return {
        "path": path,
        "settings": settings,
        "time_s": time_s,
        "rel_rmse": error,
        "rmse": error,
        "max_abs": 1.0,
    }


REPORT_POINTS = [
    _point("jax", 1.0, 0.2, "none", 1),
    _point("jax", 2.0, 0.012, "opacity-maps", 1, 4),
    _point("jax", 3.0, 0.008, "opacity-maps", 1, 16),
    _point("jax", 9.0, 0.004, "opacity-maps", 2, 16),
    _point("jax", 10.0, 0.009, "opacity-maps", 2, 4),  # dominated
    _point("jax", 4.0, 0.15, "none", 2),  # dominated
    _point("gl", 0.5, 0.2, "none", 1),
    _point("gl", 1.0, 0.0009, "opacity-maps", 1, 4),
    {
        "path": "gl",
        "settings": {"shadows": "opacity-maps", "maps": 16, "supersampling": 1},
        "skipped": "too big",
    },
]
REPORT_CONFIG = {
    "scene": "s",
    "size": [8, 8],
    "repeats": 1,
    "timing": "measured",
    "reference": {"shadows": "exact at 16²", "ordering": "exact", "supersampling": 2},
    "space": REPORT_SPACE.to_json(),
    "search": {"stop_at": 5e-4, "budget": None},
    "paths": ["jax", "gl"],
}


def test_the_report(tmp_path):
    files = write_report(tmp_path, REPORT_POINTS, REPORT_CONFIG)
    assert files["pareto"].read_text().splitlines() == [
        "path,shadows,maps,supersampling,time_s,rel_rmse,rmse,max_abs",
        "jax,none,,1,1.0,0.2,0.2,1.0",
        "jax,opacity-maps,4,1,2.0,0.012,0.012,1.0",
        "jax,opacity-maps,16,1,3.0,0.008,0.008,1.0",
        "jax,opacity-maps,16,2,9.0,0.004,0.004,1.0",
        "gl,none,,1,0.5,0.2,0.2,1.0",
        "gl,opacity-maps,4,1,1.0,0.0009,0.0009,1.0",
    ]
    assert len(files["csv"].read_text().splitlines()) == 1 + 8  # every measured point
    text = files["summary"].read_text()
    assert "| 1.0% | jax | 3 | 0.800% | shadows opacity-maps, maps 16, supersampling 1 |" in text
    assert "| 0.5% | jax | 9 | 0.400% | shadows opacity-maps, maps 16, supersampling 2 |" in text
    assert "| 0.1% | gl | 1 | 0.090% | shadows opacity-maps, maps 4, supersampling 1 |" in text
    # 0.1 % out of jax's reach: its best point has both knobs at their largest values, and
    # no shadows at 2 × 2 samples did worse.
    floors = "maps at its largest value (16); supersampling at its largest value (2); "
    assert f"| 0.1% | jax | – | not reached | {floors}no other shadow method reduced the error |" in text
    assert "| 5 | gl | none | – | 1 | 0.5 | 20.000% |" in text  # the fronts, numbered as the plot
    assert "- gl, shadows opacity-maps, maps 16, supersampling 1: too big" in text
    assert files["plot"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_command_line(tmp_path, capsys, gl):
    toml = tmp_path / "tiny.toml"
    toml.write_text(
        'name = "tiny"\n[hair]\nsource = "furball"\nstrands = 40\npoints = 5\n'
        "[camera]\nwidth = 16\nheight = 16\n"
        '[shadows]\nmethod = "opacity-maps"\nmaps = 4\nresolution = 16\n'
    )
    out = tmp_path / "joint"
    args = [str(toml), "--joint", "--out", str(out), "--paths", "gl", "--quick", "--repeats", "1"]
    assert cli.main(["sweep", *args, "--knobs", "shadows,bins", "--budget", "5"]) == 0
    printed = capsys.readouterr().out
    assert "## Cheapest combination reaching each error" in printed and "wrote" in printed
    config = json.loads((out / "joint.json").read_text())
    assert config["space"]["knobs"] == {"shadows": list(QUICK_JOINT_KNOBS["shadows"]), "bins": [16, "exact"]}
    assert set(QUICK_JOINT_KNOBS["shadows"]) == set(shadow_method_names())  # every registered method
    assert config["search"] == {"stop_at": 5e-4, "budget": 5, "budget_s": None, "time_tolerance": 0.1}
    assert len(load_joint(out)) == 5 and (out / "pareto.csv").exists() and (out / "joint_pareto.png").exists()
    for extra, message in [
        (["--target", str(toml)], "--target is for the one-knob sweep"),
        (["--knobs", "gamma"], "unknown knob 'gamma'"),
    ]:
        assert cli.main(["sweep", *args, *extra]) == 2
        err = capsys.readouterr().err
        assert message in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert cli.main(["sweep", str(toml), "--out", str(out), "--budget", "3"]) == 2
    assert "--stop-at, --budget and --budget-s are options of --joint" in capsys.readouterr().err
    assert cli.main(["sweep", str(toml), "--out", str(out), "--knobs", "bins", "--quick"]) == 2
    assert "holds another kind of sweep (joint.json)" in capsys.readouterr().err


def test_deep_maps_are_searched_in_layers(tmp_path, gl):
    """The registered deep opacity maps, through the `layers` knob their field gives them,
    rendered: more layers, a different error (no edit of the search named them)."""
    scene = small_furball_scene(strands=60, size=24, maps=4, resolution=16)
    knobs = {"shadows": ("none", "deep"), "layers": (2, 8), "maps": (4,), "bins": ("exact",)}
    points = run_joint(scene, tmp_path, knobs=knobs, paths=("gl",), search=None, cost=_model_cost)
    assert [p["settings"] for p in points] == [
        {"shadows": "none", "bins": "exact"},
        {"shadows": "deep", "layers": 2, "bins": "exact"},
        {"shadows": "deep", "layers": 8, "bins": "exact"},
    ]
    errors = [p["rel_rmse"] for p in points]
    assert len(set(errors)) == 3 and errors[0] > max(errors[1:])  # deep shadows beat none


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(knobs={"gamma": (1,)}), "unknown knob 'gamma'"),
        (dict(knobs={"bins": ()}), "knob 'bins' has no values"),
        (dict(paths=("vulkan",)), "unknown path 'vulkan'"),
        (dict(repeats=0), r"^repeats must be a positive integer, got 0$"),
    ],
)
def test_bad_arguments_are_refused_before_any_render(tmp_path, kwargs, message, monkeypatch):
    """The joint search checks its knobs, paths and repeats as the one-knob sweep does
    (`check_run`), before a renderer is made or a folder written."""

    def no_render(path):
        raise AssertionError("a renderer was made before the arguments were checked")

    monkeypatch.setattr(search_mod, "renderer", no_render)
    with pytest.raises(SweepError, match=message):
        run_joint(small_furball_scene(), tmp_path / "out", **{"knobs": {"bins": (1,)}, **kwargs})
    assert not (tmp_path / "out").exists()
