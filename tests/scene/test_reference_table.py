"""The scene file's [reference] table (hairjax/_scene/_reference.py): defaults, values, and
one-line errors naming reference.key, as for every other table."""

from __future__ import annotations

import re

import pytest

import hairjax as hj
from hairjax._errors import SceneError
from hairjax._scene._file import load_scene

HAIR = '[hair]\nsource = "furball"\nstrands = 5\n'


def _load(tmp_path, text, overrides=None):
    path = tmp_path / "s.toml"
    path.write_text(HAIR + text)
    return load_scene(path, overrides)


def test_no_table_is_no_settings_and_an_empty_one_is_mitsubas_defaults(tmp_path):
    assert _load(tmp_path, "").reference is None
    settings = _load(tmp_path, "[reference]\n").reference
    assert settings == hj.ReferenceSettings()
    assert (settings.eumelanin, settings.pheomelanin, settings.sigma_a) == (1.3, 0.2, None)
    assert (settings.longitudinal_roughness, settings.azimuthal_roughness, settings.scale_tilt) == (
        0.3,
        0.3,
        2.0,
    )
    assert (settings.eta, settings.max_depth, settings.spp) == (1.55, 16, 64)


def test_values_and_overrides(tmp_path):
    text = "[reference]\nsigma_a = [0.4, 0.6, 1.2]\nlongitudinal_roughness = 0.2\nmax_depth = 4\n"
    settings = _load(tmp_path, text, {"reference.spp": 8, "reference.scale_tilt": -3}).reference
    assert settings.sigma_a == (0.4, 0.6, 1.2) and settings.eumelanin is None and settings.pheomelanin is None
    assert (settings.longitudinal_roughness, settings.max_depth, settings.spp, settings.scale_tilt) == (
        0.2,
        4,
        8,
        -3.0,
    )
    assert _load(tmp_path, "[reference]\nsigma_a = 0.5\n").reference.sigma_a == (0.5, 0.5, 0.5)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("sigma_a = [1, 1, 1]\neumelanin = 2.0", r"reference\.sigma_a excludes reference\.eumelanin"),
        ("eumelanin = -1", r"reference\.eumelanin must be a number >= 0, got -1"),
        ("pheomelanin = true", r"reference\.pheomelanin must be a finite number, got true \(boolean\)"),
        ("sigma_a = [1, -1, 1]", r"reference\.sigma_a must be"),
        ("longitudinal_roughness = 0", r"reference\.longitudinal_roughness must be a number in \(0, 1\]"),
        ("azimuthal_roughness = 1.5", r"reference\.azimuthal_roughness must be a number in \(0, 1\]"),
        ("scale_tilt = 60", r"reference\.scale_tilt must be a number in \[-45, 45\]"),
        ("eta = 0.9", r"reference\.eta must be a number in \[1, 3\]"),
        ("max_depth = 1", r"reference\.max_depth must be an integer >= 2, got 1"),
        ("spp = 16.0", r"reference\.spp must be an integer, got 16\.0"),
        ("samples = 4", r"unknown key reference\.samples; allowed keys in \[reference\]: eumelanin"),
    ],
)
def test_errors_name_the_file_and_the_key(tmp_path, text, message):
    with pytest.raises(SceneError, match=rf"^{re.escape(str(tmp_path / 's.toml'))}: {message}") as err:
        _load(tmp_path, f"[reference]\n{text}\n")
    assert "\n" not in str(err.value)
