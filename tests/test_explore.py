"""`explore(scene)`: the live panel's sliders drive the staged renderer — shading sliders
re-run only the shading stage, light sliders the geometry stage too — and the picture it
shows is the true render."""

from __future__ import annotations

import base64
import io
import math

import numpy as np
import pytest
from helpers import scheuermann_scene, small_furball_scene

import hairjax as hj
from hairjax import _explore
from hairjax._explore import explore, light_angles, light_from_angles, slider_range
from hairjax._io._image import linear_to_srgb

widgets = pytest.importorskip("ipywidgets")
PIL = pytest.importorskip("PIL.Image")


def decoded(png: bytes) -> np.ndarray:
    """The panel's PNG as `[H, W, 3]` 8-bit integers."""
    return np.asarray(PIL.open(io.BytesIO(png)).convert("RGB"), dtype=np.int64)


def tonemap(image) -> np.ndarray:
    """The 8-bit sRGB of a linear render, written out here rather than through the
    panel's PNG writer: clip to [0, 1], sRGB, round to 8 bits."""
    return np.round(linear_to_srgb(np.asarray(image, np.float64)[..., :3]) * 255).astype(np.int64)


@pytest.fixture
def counted(monkeypatch):
    """Count the panel's geometry-stage calls independently of its own counter."""
    calls = []

    def counting(scene, *args, **kwargs):
        calls.append(scene)
        return hj.geometry_stage(scene, *args, **kwargs)

    monkeypatch.setattr(_explore, "geometry_stage", counting)
    return calls


def test_shading_sliders_rerun_only_the_shading_stage(counted):
    panel = explore(small_furball_scene())
    assert isinstance(panel.widget, widgets.HBox)
    assert set(panel.sliders) == {
        "kd",
        "ks",
        "shininess",
        "kappa",
        "ambient",
        "light_azimuth",
        "light_elevation",
    }
    pictures = [panel.png]
    for name, value in (("ks", 0.9), ("shininess", 80.0), ("kd", 0.2), ("kappa", 0.1)):
        panel.sliders[name].value = value
        assert panel.png != pictures[-1], name  # each move shows a new picture
        pictures.append(panel.png)
    assert panel.geometry_runs == 1 and len(counted) == 1
    assert panel.shading_runs == 5  # the first picture and four moves


def test_the_picture_is_the_render(counted):
    """The shown PNG decodes to tonemap(render(scene with the sliders' values))."""
    scene = small_furball_scene()
    panel = explore(scene)
    panel.sliders["ks"].value = 0.7
    panel.sliders["kd"].value = 0.3  # Kd (0.6, 0.4, 0.3) scaled: its hue is kept
    panel.sliders["shininess"].value = 50.0
    params = hj.ShadingParams(kd=(0.3, 0.2, 0.15), ks=0.7, shininess=50.0, kappa=0.8, ambient=0.05)
    expected = tonemap(hj.render(scene.replace(params=params)))
    shown = decoded(panel.png)
    # The panel compiles its own shading function: its float32 sums may round apart from
    # render's by a few ulps, so a value on an 8-bit rounding boundary may land one step away.
    diff = np.abs(shown - expected)
    assert diff.max() <= 1
    assert np.mean(diff > 0) < 0.01
    assert expected.std() > 10  # a picture, not a black square


def test_light_slider_reruns_geometry_and_shows_that_light(counted):
    scene = small_furball_scene()
    panel = explore(scene)
    before = panel.png
    panel.sliders["light_azimuth"].value = -60.0
    panel.sliders["light_elevation"].value = 10.0
    assert panel.png != before
    assert panel.geometry_runs == 3 and len(counted) == 3  # once, then once per light move
    # Azimuth −60°, elevation 10°: the light comes from u, and travels along −u.
    a, e = math.radians(-60.0), math.radians(10.0)
    u = np.array([math.cos(e) * math.sin(a), math.sin(e), math.cos(e) * math.cos(a)])
    lit = scene.replace(light=hj.Light(direction=tuple(-u)))
    diff = np.abs(decoded(panel.png) - tonemap(hj.render(lit)))
    assert diff.max() <= 1  # one 8-bit step at most, as in test_the_picture_is_the_render


def test_light_angles_round_trip():
    scene = small_furball_scene()  # light direction (−0.5, −0.7, −0.4): from upper right, in front
    azimuth, elevation = light_angles(scene)
    assert 0 < azimuth < 90 and 0 < elevation < 90
    back = light_from_angles(scene, azimuth, elevation).direction
    unit = -np.array((-0.5, -0.7, -0.4)) / np.linalg.norm((-0.5, -0.7, -0.4))
    np.testing.assert_allclose(back, -unit, atol=1e-12)  # float64 trigonometry, a few ulps
    point = scene.replace(light=hj.Light(kind="point", position=(0.0, 2.0, 0.0)))
    assert light_angles(point) == pytest.approx((0.0, 90.0))
    moved = light_from_angles(point, 90.0, 0.0).position
    np.testing.assert_allclose(moved, (2.0, 0.0, 0.0), atol=1e-12)  # same distance, now +x


def test_slider_ranges_follow_the_parameter_checks():
    params = hj.ShadingParams(kd=(0.6, 0.4, 0.3), ks=0.4, shininess=30.0, kappa=0.8)
    assert slider_range(params, "shininess") == ("log", 0.0, 3.0)  # p > 0: 1 … 1000
    assert slider_range(params, "kd") == ("linear", 0.0, pytest.approx(1.2))  # ≥ 0
    assert slider_range(params, "kappa") == ("linear", 0.0, pytest.approx(1.6))
    scheuermann = hj.ScheuermannParams(primary_shift=0.1)
    assert slider_range(scheuermann, "primary_shift") == ("linear", -1.0, 1.0)  # any finite shift


def test_the_shininess_slider_spans_the_declared_range():
    """Kajiya-Kay declares the shininess's range (0.5 … 10⁴, its plateau scan's): the slider
    spans it, logarithmic as the fit's transform; κ, undeclared, keeps its check's slider."""
    params = hj.ShadingParams(kd=(0.6, 0.4, 0.3), ks=0.4, shininess=30.0, kappa=0.8)
    assert slider_range(params, "shininess", hj.KajiyaKay) == ("log", math.log10(0.5), 4.0)
    assert slider_range(params, "kappa", hj.KajiyaKay) == ("linear", 0.0, pytest.approx(1.6))
    panel = explore(small_furball_scene())
    shininess = panel.sliders["shininess"]
    assert isinstance(shininess, widgets.FloatLogSlider)
    assert (shininess.min, shininess.max) == (math.log10(0.5), 4.0) and shininess.value == 20.0


def test_scheuermann_scene_gets_its_own_sliders(counted):
    panel = explore(scheuermann_scene())
    fields = set(panel.sliders) - {"light_azimuth", "light_elevation"}
    assert fields == {
        "kd",
        "ambient",
        "primary_color",
        "primary_exponent",
        "primary_shift",
        "secondary_color",
        "secondary_exponent",
        "secondary_shift",
        "kappa",
    }
    before = panel.png
    panel.sliders["primary_shift"].value = -0.4
    assert panel.png != before
    assert len(counted) == 1


def test_static_fallback_is_the_picture():
    panel = explore(small_furball_scene())
    bundle = panel._repr_mimebundle_()
    assert "application/vnd.jupyter.widget-view+json" in bundle
    assert base64.b64decode(bundle["image/png"]) == panel.png
