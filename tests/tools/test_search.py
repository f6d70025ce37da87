"""The one engine (hairjax/tools/_search.py, _store.py, _knob_space.py's OneKnobSpace): the
one-knob space, the store's two layouts, and what the sweep shares with the joint search."""

import json

import pytest
from helpers import small_furball_scene

from hairjax.tools import (
    OneKnobSpace,
    SearchConfig,
    SweepError,
    knob_scene,
    run_search,
    run_sweep,
    settings_scene,
)
from hairjax.tools._store import JOINT_STORE, SWEEP_STORE, store_of


@pytest.fixture(scope="module")
def scene():
    return small_furball_scene(strands=30, size=16, maps=4, resolution=16)


def test_the_one_knob_space(scene):
    space = OneKnobSpace({"bins": (1, "exact"), "width": (0.5, 2.0), "maps": (4,)})
    assert list(space.grid()) == [
        {"bins": 1},
        {"bins": "exact"},
        {"width": 0.5},
        {"width": 2.0},
        {"maps": 4},
    ]
    assert space.size() == 5 and space.label({"width": 0.5}) == "width = 0.5"
    assert OneKnobSpace.from_json(json.loads(json.dumps(space.to_json()))) == space
    # A setting changes its one knob; the others keep the scene's settings.
    for setting in space.grid():
        ((knob, value),) = setting.items()
        variant, s = settings_scene(scene, setting)
        expected, s_expected = knob_scene(scene, knob, value)
        assert s == s_expected and variant.shadows == expected.shadows
        assert variant.ordering == expected.ordering


def test_the_store_layouts():
    point = {"path": "gl", "settings": {"maps": 16}, "time_s": 1.5, "rel_rmse": 0.01}
    record = SWEEP_STORE.record(point)
    assert list(record) == ["path", "knob", "value", "time_s", "rel_rmse"]
    assert record == {"path": "gl", "knob": "maps", "value": 16, "time_s": 1.5, "rel_rmse": 0.01}
    assert SWEEP_STORE.point(record) == {**record, "settings": {"maps": 16}}
    assert SWEEP_STORE.record(SWEEP_STORE.point(record)) == record
    assert JOINT_STORE.record(point) == point == JOINT_STORE.point(point)
    assert store_of({"knobs": {}}) is SWEEP_STORE and store_of({"space": {}}) is JOINT_STORE


def test_a_sweep_with_a_cost_model_is_timed_by_it_and_keeps_its_timing(scene, tmp_path):
    """The sweep takes the joint search's cost model: only the error's render is made, the
    time is the model's, and the folder remembers it (a measured run is refused there)."""
    costs = {1: 0.25, "exact": 4.0}
    points = run_sweep(
        scene,
        tmp_path,
        knobs={"bins": (1, "exact")},
        paths=("jax",),
        progress=False,
        cost=lambda s: costs[s["bins"]],
    )
    assert [(p["value"], p["time_s"], p["times"]) for p in points] == [(1, 0.25, []), ("exact", 4.0, [])]
    assert json.loads((tmp_path / "sweep.json").read_text())["timing"] == "cost model"
    with pytest.raises(SweepError, match="holds a sweep of other settings"):
        run_sweep(scene, tmp_path, knobs={"bins": (1,)}, paths=("jax",), repeats=1, progress=False)


def test_the_pareto_search_needs_a_space_of_combinations(scene, tmp_path):
    space = OneKnobSpace({"bins": (1, 4)})
    with pytest.raises(TypeError, match="steps through a KnobSpace"):
        run_search(
            scene,
            tmp_path / "out",
            space,
            store=SWEEP_STORE,
            paths=("jax",),
            repeats=1,
            search=SearchConfig(),
        )
    assert not (tmp_path / "out").exists()


def test_the_sweep_and_the_joint_search_measure_a_setting_alike(scene, tmp_path):
    """One setting of both spaces, measured by the sweep and by the joint search (every
    combination of one knob): the same errors, against the same reference."""
    from hairjax.tools import run_joint

    sweep = run_sweep(scene, tmp_path / "s", knobs={"bins": (4,)}, paths=("jax",), repeats=1, progress=False)
    joint = run_joint(scene, tmp_path / "j", knobs={"bins": (4,)}, paths=("jax",), repeats=1, search=None)
    assert sweep[0]["settings"] == joint[0]["settings"] == {"bins": 4}
    for key in ("rmse", "max_abs", "rel_rmse", "tau_rmse", "tau_max"):
        assert sweep[0][key] == joint[0][key], key
    assert sweep[0]["rmse"] > 0  # four bins do change the order
