"""`save_scene` (hairjax/_scene/_save.py): a scene written as TOML reads back to the same
scene and renders the same image, bit for bit."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from helpers import DATA, EXAMPLES, first_then_slow

import hairjax as hj
from hairjax._errors import SceneError
from hairjax._scene._file import scene_for_hair

# Small images and maps, so each scene renders in a second or two; the overrides go
# through the file like the file's own keys, so the saved scene holds them.
SMALL = {"camera.width": 40, "camera.height": 32}


def same(a, b, where="scene") -> None:
    """Every field of two scenes equal: arrays element for element, dataclasses and
    equinox modules field by field."""
    if dataclasses.is_dataclass(a) and not isinstance(a, type):
        assert type(a) is type(b), where
        for f in dataclasses.fields(a):
            same(getattr(a, f.name), getattr(b, f.name), f"{where}.{f.name}")
    elif isinstance(a, dict):
        assert a.keys() == b.keys(), where
        for k in a:
            same(a[k], b[k], f"{where}[{k!r}]")
    elif a is None or isinstance(a, (str, bool)):
        assert a == b, where
    else:
        x, y = np.asarray(a), np.asarray(b)
        assert x.dtype == y.dtype and np.array_equal(x, y), f"{where}: {x} != {y}"


def round_trip(scene: hj.Scene, tmp_path) -> hj.Scene:
    path = hj.save_scene(scene, tmp_path / "saved.toml")
    again = hj.load_scene(path)
    same(scene, again)
    first, second = np.asarray(hj.render(scene)), np.asarray(hj.render(again))
    assert np.array_equal(first, second)  # the same scene: the same image, bit for bit
    return again


CASES = {
    "default": (hj.default_scene_path(), {**SMALL, "hair.strands": 300, "shadows.resolution": 32}),
    "scheuermann": (EXAMPLES / "scheuermann.toml", SMALL),
    "patches and an occluder": (EXAMPLES / "patches.toml", SMALL),
    "a hair file": (EXAMPLES / "tressfx_ponytail.toml", SMALL),
    "deep shadows, a point light": (EXAMPLES / "point_light.toml", SMALL),
}


@pytest.mark.parametrize("case", first_then_slow(CASES))
def test_a_saved_scene_reads_back_to_the_same_scene_and_image(case, tmp_path):
    path, overrides = CASES[case]
    if case == "a hair file" and not (DATA / "tressfx" / "ponytail_side.tfx").exists():
        pytest.skip(f"no hair assets in {DATA}")
    scene = hj.load_scene(path, overrides)
    round_trip(scene, tmp_path)


def test_a_framed_hair_file_is_saved_with_its_camera_and_widths(tmp_path):
    hair = next(iter(sorted((DATA / "hair").glob("*.hair"))), None)
    if hair is None:
        pytest.skip(f"no .hair assets in {DATA}")
    scene = scene_for_hair(hair, width=24, height=24, overrides={"camera.azimuth": 180})
    again = round_trip(scene, tmp_path)
    assert again.strands.width_units == "world"


def test_fitted_parameters_are_written_as_values(tmp_path):
    scene = hj.load_scene(hj.default_scene_path(), {**SMALL, "hair.strands": 50})
    fitted = scene.replace(params=hj.ShadingParams(kd=(0.1, 0.2, 0.3), ks=0.7, shininess=55.5, kappa=2.0))
    text = hj.save_scene(fitted, tmp_path / "f.toml").read_text()
    assert "kd = [0.1, 0.2, 0.3]" in text and "shininess = 55.5" in text  # shortest decimals
    again = hj.load_scene(tmp_path / "f.toml")
    same(fitted.params, again.params)


def test_a_scene_a_file_cannot_describe_is_refused(tmp_path):
    built = hj.Scene(hj.furball(strands=10, points=4))
    with pytest.raises(SceneError, match=r"came from no scene file's \[hair\] table"):
        hj.save_scene(built, tmp_path / "s.toml")
    loaded = hj.load_scene(hj.default_scene_path())
    with pytest.raises(SceneError, match="replaced"):
        hj.save_scene(loaded.replace(strands=built.strands), tmp_path / "s.toml")
    with pytest.raises(SceneError, match=r"ends in \.toml"):
        hj.save_scene(loaded, tmp_path / "s.json")
    assert list(tmp_path.iterdir()) == []


def test_parameter_classes_print_their_values():
    assert repr(hj.ShadingParams(kd=(0.5, 0.25, 0.125), ks=0.3, shininess=40.0, kappa=1.0)) == (
        "ShadingParams(kd=[0.5, 0.25, 0.125], ks=[0.3, 0.3, 0.3], shininess=40, kappa=1, ambient=[0, 0, 0])"
    )
    assert repr(hj.LightParams(direction=(0.0, -1.0, 0.0))) == "LightParams(direction=[0, -1, 0], color=None)"
    text = repr(hj.ScheuermannParams(primary_exponent=12.5))
    assert text.startswith("ScheuermannParams(kd=[0.6, 0.6, 0.6], ") and "primary_exponent=12.5" in text
