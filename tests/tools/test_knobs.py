"""The sweep's knobs (hairjax/tools/_knobs.py): the shadow method as a knob, the knobs
setting a method's fields, and settings of several knobs at once."""

import dataclasses

import numpy as np
import pytest
from helpers import small_furball_scene

import hairjax as hj
from hairjax._geometry._shadows import AbstractShadowMethod, register_shadow_method, shadow_method_names
from hairjax._geometry._shadows._base import SHADOW_METHODS
from hairjax.tools import KNOBS, knob_scene, knob_space, one_knob_space, settings_scene
from hairjax.tools._knobs import method_options


@pytest.fixture(scope="module")
def scene():
    return small_furball_scene(strands=30, size=16, maps=4, resolution=16)


def test_the_shadows_knob_lists_every_registered_method_none_first():
    assert set(KNOBS["shadows"]) == set(shadow_method_names())
    assert KNOBS["shadows"][0] == "none"  # the one casting no shadows: the cheapest


def test_the_shadows_knob_keeps_the_options_the_method_takes(scene):
    exact, s = knob_scene(scene, "shadows", "exact")
    assert exact.shadows == hj.Shadows("exact", resolution=16) and s == 1
    assert knob_scene(scene, "shadows", "none")[0].shadows == hj.Shadows("none")
    # Back from exact shadows, which have no map count: the method's default count.
    maps = knob_scene(exact, "shadows", "opacity-maps")[0].shadows
    default = hj.Shadows("opacity-maps").maps
    assert maps == hj.Shadows("opacity-maps", maps=default, resolution=16)


def test_a_setting_of_several_knobs(scene):
    setting = {"bins": "exact", "width": 2.0, "map_resolution": 32, "maps": 8, "shadows": "opacity-maps"}
    variant, s = settings_scene(scene.replace(shadows=hj.Shadows("none")), {**setting, "supersampling": 2})
    assert s == 2 and variant.shadows == hj.Shadows("opacity-maps", 8, 32)  # method set first
    assert variant.ordering == hj.Ordering("exact")
    np.testing.assert_allclose(variant.strands.width, 2 * scene.strands.width)
    assert settings_scene(scene, {}) == (scene, 1)


def test_the_one_knob_sweep_drops_knobs_the_scene_s_method_lacks(scene):
    knobs = {"maps": (1,), "map_resolution": (16,), "layers": (2,), "shadows": ("none",), "bins": (1,)}
    assert list(one_knob_space(scene, knobs).knobs) == ["maps", "map_resolution", "shadows", "bins"]
    exact = scene.replace(shadows=hj.Shadows("exact", resolution=16))
    assert list(one_knob_space(exact, knobs).knobs) == ["map_resolution", "shadows", "bins"]
    assert list(one_knob_space(scene.replace(shadows=hj.Shadows("none")), knobs).knobs) == ["bins"]


@pytest.fixture
def layered():
    """A shadow method with a `layers` field, registered for the test (as deep opacity maps
    would be), then removed."""

    @register_shadow_method
    @dataclasses.dataclass(frozen=True)
    class Layered(AbstractShadowMethod):
        method = "layered-test"
        layers: int = 4
        resolution: int = 256
        layer_spacing: float = 1.0

        def setup(self, *args, **kwargs):
            raise NotImplementedError

        def omega(self, setup, alpha):
            raise NotImplementedError

    yield Layered
    del SHADOW_METHODS.classes["layered-test"]


def test_a_method_with_a_layers_field_is_searched_in_layers(scene, layered):
    assert method_options("layered-test") == ("map_resolution", "layers")
    knobs = {"shadows": ("none", "layered-test"), "maps": (4,), "map_resolution": (16, 32), "layers": (2, 8)}
    space = knob_space(scene, knobs)
    assert "maps" not in space.knobs  # no method of the space has a map count
    assert {"shadows": "layered-test", "map_resolution": 32, "layers": 8} in list(space.grid())
    variant, _ = settings_scene(scene, {"shadows": "layered-test", "layers": 8, "map_resolution": 32})
    assert variant.shadows == layered(layers=8, resolution=32, layer_spacing=1.0)
