"""`hairjax.distill`: the views it derives, its refusals (before any work), a fit that
recovers a model from that model's own renders, and, where Mitsuba is installed, the
reference rendered, fitted and measured end to end."""

from __future__ import annotations

import dataclasses
import importlib.util
import math
import sys

import numpy as np
import pytest

import hairjax as hj
from hairjax._distill import view_scene
from hairjax._errors import MissingDependency, SceneError

NEEDS_MITSUBA = pytest.mark.skipif(
    importlib.util.find_spec("mitsuba") is None,
    reason="the [reference] extra is not installed: pip install 'hairjax[reference]'",
)


def _scene(size=20, strands=60):
    return hj.Scene(
        hj.furball(strands, 6, seed=2),
        camera=hj.Camera(eye=(0.0, 0.3, 4.2), target=(0.0, -0.1, 0.0), fov=40.0, width=size, height=size),
        light=hj.Light(direction=(-0.6, -0.8, -0.5)),
        background=(0.02, 0.02, 0.03),
        name="furball",
    )


def _angle(a, b) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    return math.degrees(math.acos(np.clip(a @ b / np.linalg.norm(a) / np.linalg.norm(b), -1, 1)))


def test_views_turn_the_camera_about_its_up_vector_and_derive_the_lights():
    # A tilted up vector: the turn is about it, not about y.
    scene = _scene()
    up = np.array([0.3, 1.0, 0.1]) / np.linalg.norm([0.3, 1.0, 0.1])
    scene = scene.replace(camera=hj.Camera(eye=(0.5, 0.3, 4.2), target=(0.0, -0.1, 0.0), up=tuple(up)))
    target = np.asarray(scene.camera.target)
    before = np.subtract(scene.camera.eye, target)
    for azimuth in (60.0, -50.0, 120.0):
        turned = view_scene(scene, hj.experimental.DistillView("v", azimuth, "key"))
        after = np.subtract(turned.camera.eye, target)
        assert np.linalg.norm(after) == pytest.approx(np.linalg.norm(before))
        assert after @ up == pytest.approx(before @ up)  # the height along up is kept
        flat = [v - (v @ up) * up for v in (before, after)]
        assert _angle(*flat) == pytest.approx(abs(azimuth))
        # The sign: a positive turn is counter-clockwise seen from above (right-handed).
        assert np.sign(np.cross(flat[0], flat[1]) @ up) == np.sign(azimuth)
        assert turned.light == scene.light and turned.camera.target == scene.camera.target
    back = np.asarray(view_scene(scene, hj.experimental.DistillView("b", 0.0, "back")).light.direction)
    to_eye = before / np.linalg.norm(before)
    assert np.linalg.norm(back) == pytest.approx(1.0)
    assert back @ to_eye > 0.8 and back @ up < 0  # towards the eye, and downwards: from above
    side = np.asarray(view_scene(scene, hj.experimental.DistillView("s", 0.0, "side")).light.direction)
    key = np.asarray(scene.light.direction) / np.linalg.norm(scene.light.direction)
    assert side @ up == pytest.approx(key @ up)
    assert _angle(key - (key @ up) * up, side - (side @ up) * up) == pytest.approx(90.0)


def test_the_default_views_train_three_and_hold_one_out():
    assert [v.name for v in hj.experimental.DISTILL_VIEWS] == ["front", "side", "back-lit", "held-out"]
    assert [v.train for v in hj.experimental.DISTILL_VIEWS] == [True, True, True, False]


def test_a_missing_mitsuba_is_refused_before_any_work(monkeypatch):
    monkeypatch.setitem(sys.modules, "mitsuba", None)  # `import mitsuba` raises ImportError

    def never(*args, **kwargs):
        raise AssertionError("work started before Mitsuba was checked")

    monkeypatch.setattr("hairjax._distill.fit", never)
    monkeypatch.setattr("hairjax._reference.reference_image", never)
    with pytest.raises(MissingDependency, match=r"pip install 'hairjax\[reference\]'"):
        hj.distill(_scene(), "marschner", eumelanin=0.3)


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        (
            dict(views=[hj.experimental.DistillView("a"), hj.experimental.DistillView("a", 30.0)]),
            ValueError,
            "unique",
        ),
        (dict(views=[hj.experimental.DistillView("a", train=False)]), ValueError, "no training view"),
        (dict(views=[hj.experimental.DistillView("a", light="top")]), ValueError, "key, back or side"),
        (dict(views=[hj.experimental.DistillView("a", math.nan)]), ValueError, "azimuth"),
        (dict(references={"front": np.zeros((20, 20, 4))}), ValueError, "no view 'side'"),
        (dict(model="phong"), SceneError, "distill: shading.model must be one of"),
        (dict(roughness=0.0), SceneError, "distill: reference.longitudinal_roughness"),
        (dict(noise_floor=True, seed=2**32 - 1), ValueError, "seed"),
    ],
    ids=["same-name", "no-training", "light", "azimuth", "references", "model", "roughness", "seed"],
)
def test_bad_input_is_one_line_before_any_work(monkeypatch, kwargs, error, match):
    def never(*args, **kwargs):
        raise AssertionError("work started before the input was checked")

    monkeypatch.setattr("hairjax._distill.fit", never)
    monkeypatch.setattr("hairjax._reference.reference_image", never)
    monkeypatch.setattr("hairjax._reference._support.import_mitsuba", lambda: None)  # present or not
    with pytest.raises(error, match=match) as info:
        hj.distill(_scene(), **{"model": "marschner", **kwargs})
    assert "\n" not in str(info.value)


def test_gains_are_recovered_from_the_models_own_renders():
    """The cheapest full distillation: Kajiya-Kay's gains (one linear solve) from its own
    renders under the default views; the held-out view is matched too."""
    scene = _scene(size=12, strands=30)
    # The defaults but for the fitted gains: distill starts a named model from its defaults.
    truth = dataclasses.replace(hj.KajiyaKay().params, kd=(0.3, 0.2, 0.1), ks=0.05, ambient=0.0)
    model = hj.KajiyaKay(truth)
    references = {
        v.name: np.asarray(hj.render(view_scene(scene.replace(shading=model), v)))
        for v in hj.experimental.DISTILL_VIEWS
    }
    d = hj.distill(scene, "kajiya-kay", references=references, fit_names=("kd", "ks"))
    # One least-squares solve in float64 on float32 targets (rounded to 6e-8 relative per
    # pixel): the gains come back within about 1e-8; 1e-6 says "found".
    np.testing.assert_allclose(np.asarray(d.params.kd), truth.kd, rtol=1e-6)
    np.testing.assert_allclose(np.asarray(d.params.ks), truth.ks, rtol=1e-6)
    assert d.holdout_rmse < 1e-6 and set(d.rmse) == {v.name for v in hj.experimental.DISTILL_VIEWS}


@pytest.mark.slow
def test_a_model_is_recovered_from_its_own_renders():
    """References made by the real-time model itself at known parameters: the fit over the
    training views finds them, and the held-out view, never fitted, is matched as well."""
    scene = _scene()
    truth = hj.MarschnerParams(
        eumelanin=0.8, pheomelanin=0.3, longitudinal_roughness=0.25, tilt=3.0, ambient=0.0
    )
    model = hj.Marschner(truth)
    references = {
        v.name: np.asarray(hj.render(view_scene(scene.replace(shading=model), v)))
        for v in hj.experimental.DISTILL_VIEWS
    }
    start = hj.Marschner(
        hj.MarschnerParams(eumelanin=1.3, pheomelanin=0.2, longitudinal_roughness=0.3, ambient=0.0)
    )
    names = ("eumelanin", "pheomelanin", "longitudinal_roughness", "tilt")
    d = hj.distill(scene, start, references=references, fit_names=names, max_steps=60)
    for name in names:
        # The suite runs in float64 with the fit's rtol 1e-8: a converged fit recovers the
        # truth to about 1e-8 here; 1e-6 says "found", with room for another BLAS.
        fitted, true = float(np.asarray(getattr(d.params, name))), float(np.asarray(getattr(truth, name)))
        assert fitted == pytest.approx(true, rel=1e-6), name
    assert d.result.termination == "converged" and d.holdout_rmse < 1e-6
    assert d.rmse["held-out"] == pytest.approx(d.holdout_rmse, rel=1e-3, abs=1e-9)
    assert set(d.images) == set(references) and d.floors == {}
    assert isinstance(d.model, hj.Marschner)
    assert float(d.model.params.eumelanin) == float(d.params.eumelanin)
    assert d.floor(train=True) is None


@pytest.mark.slow
@NEEDS_MITSUBA
def test_the_reference_is_rendered_fitted_and_measured(monkeypatch):
    scene = _scene(size=16, strands=40)
    settings = dict(eumelanin=0.3, pheomelanin=0.0, roughness=0.3, spp=4)
    d = hj.distill(scene, "kajiya-kay-mirror", **settings, noise_floor=True, max_steps=5)
    # The front view is the scene itself: its reference is the scene's at seed 0 and 1.
    ref = hj.ReferenceSettings(eumelanin=0.3, pheomelanin=0.0, longitudinal_roughness=0.3, spp=4)
    plain = scene.replace(reference=ref)
    np.testing.assert_array_equal(d.references["front"], hj.reference_image(plain, seed=0))
    np.testing.assert_array_equal(d.second["front"], hj.reference_image(plain, seed=1))
    assert d.result.rmse < math.sqrt(
        np.mean([np.mean(d.references[v.name][..., :3] ** 2) for v in d.views if v.train])
    )  # the fit explains some of the image: below the RMSE of a black render
    assert d.rmse["held-out"] == pytest.approx(d.holdout_rmse, rel=1e-5)
    assert set(d.floors) == {v.name for v in d.views} and all(f > 0 for f in d.floors.values())
    assert d.floor(train=False) == pytest.approx(d.floors["held-out"])
    # Another model on the same references: nothing rendered again, the same targets.
    monkeypatch.setattr("hairjax._reference.reference_image", None)  # a render would fail
    pairs = {v: (d.references[v], d.second[v]) for v in d.references}
    again = hj.distill(scene, "kajiya-kay", references=pairs, max_steps=5)
    assert again.floors == d.floors
    np.testing.assert_array_equal(again.references["side"], d.references["side"])
