"""--set, --seed and --size: the scene a command reads, with the command line's changes."""

from __future__ import annotations

import argparse

import numpy as np
import pytest

import hairjax as hj
from hairjax.cli import main
from hairjax.cli._parser import build_parser
from hairjax.cli._scenes import load_cli_scene

SCENE = """
[hair]
source = "furball"
strands = 40
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
    path = tmp_path / "s.toml"
    path.write_text(SCENE)
    return path


def _scene(scene_file, *options) -> hj.Scene:
    args = build_parser().parse_args(["render", str(scene_file), *options])
    return load_cli_scene(args, args.scene)


def test_set_reads_toml_values_and_bare_strings(scene_file):
    scene = _scene(
        scene_file,
        "--set",
        "shading.kd=0.25",
        "--set",
        "light.direction=[0, 1, 0]",
        "--set",
        "camera.fov=30",
        "--set",
        "ordering.method=none",
    )
    np.testing.assert_allclose(np.asarray(scene.params.kd), 0.25)
    assert scene.camera.fov == 30.0
    assert type(scene.ordering).__name__ == "IndexOrder"
    expected = hj.Light(direction=(0.0, 1.0, 0.0)).direction
    np.testing.assert_allclose(scene.light.direction, expected)


@pytest.mark.parametrize(
    "assignment, message",
    [
        ("camera.widht=3", "[camera] has no key 'widht'"),
        ("camra.width=3", "no table [camra]"),
        ("camera.width=0", "camera.width"),
        ("shading.kd=-1", "shading.kd"),
        ("hair.strands=many", "hair.strands"),
    ],
)
def test_a_bad_set_is_one_line_naming_the_key(scene_file, assignment, message, capsys):
    assert main(["render", str(scene_file), "--set", assignment, "-o", "x.exr"]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1


def test_a_typo_lists_the_allowed_keys(scene_file, capsys):
    main(["render", str(scene_file), "--set", "camera.widht=3"])
    assert "keys: frame, eye, target" in capsys.readouterr().err


def test_seed_changes_procedural_hair(scene_file):
    a, b = _scene(scene_file, "--seed", "1"), _scene(scene_file, "--seed", "2")
    assert not np.array_equal(a.strands.points, b.strands.points)
    np.testing.assert_array_equal(a.strands.points, _scene(scene_file, "--seed", "1").strands.points)


def test_size_keeps_the_aspect_or_sets_both(scene_file):
    scene = _scene(scene_file, "--size", "80")
    assert (scene.camera.width, scene.camera.height) == (80, 60)  # the file's 40×30, doubled
    scene = _scene(scene_file, "--size", "64x16")
    assert (scene.camera.width, scene.camera.height) == (64, 16)
    default = load_cli_scene(argparse.Namespace(size=(100, None)), None)
    base = hj.load_scene(hj.default_scene_path()).camera
    assert (default.camera.width, default.camera.height) == (100, round(100 * base.height / base.width))


def test_size_wins_over_set(scene_file):
    scene = _scene(scene_file, "--set", "camera.width=10", "--size", "20x20")
    assert scene.camera.width == 20
