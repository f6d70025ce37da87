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


def test_switching_the_shadow_method_drops_the_keys_it_does_not_read(scene_file, tmp_path, capsys):
    """The file's [shadows] has maps = 4 and resolution = 32; "exact" reads resolution
    only: maps is dropped, with one warning naming it."""
    with pytest.warns(UserWarning, match=r"shadows\.method = 'exact' does not read shadows\.maps: dropped$"):
        scene = _scene(scene_file, "--set", 'shadows.method="exact"')
    assert scene.shadows.method == "exact" and scene.shadows.resolution == 32
    out = str(tmp_path / "x.exr")
    assert main(["render", "--set", "shadows.method=exact", "--size", "8", "-o", out, "-q"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    warning = "shadows.method = 'exact' does not read shadows.maps: dropped"
    assert err == [f"hairjax: warning: {hj.default_scene_path()}: {warning}"]


def test_switching_the_model_and_the_ordering_keeps_keys_set_on_the_command_line(scene_file):
    scene_file.write_text(SCENE + "[shading]\nkd = 0.4\nks = 0.2\nshininess = 20.0\n[ordering]\nbins = 8\n")
    with pytest.warns(UserWarning) as caught:
        scene = _scene(
            scene_file,
            "--set",
            'shading.model="scheuermann"',
            "--set",
            "shading.primary_exponent=12.0",
            "--set",
            'ordering.method="none"',
        )
    messages = sorted(str(w.message).split(": ", 1)[1] for w in caught)
    assert messages == [
        "ordering.method = 'none' does not read ordering.bins: dropped",
        "shading.model = 'scheuermann' does not read shading.ks, shading.shininess: dropped",
    ]
    assert type(scene.shading).__name__ == "Scheuermann"
    assert float(scene.params.primary_exponent) == 12.0 and float(scene.params.kd[0]) == pytest.approx(0.4)
    assert type(scene.ordering).__name__ == "IndexOrder"


def test_unset_removes_a_key(scene_file):
    assert _scene(scene_file).shadows.maps == 4
    scene = _scene(scene_file, "--unset", "shadows.maps", "--unset", "camera.height")
    assert scene.shadows.maps == hj.Shadows("opacity-maps").maps  # the default
    assert scene.camera.height == hj.Camera().height
    with pytest.warns(UserWarning, match="does not read shadows.maps, shadows.resolution"):
        assert _scene(scene_file, "--set", 'shadows.method="none"').shadows.method == "none"


@pytest.mark.parametrize(
    "options, message",
    [
        (["--unset", "camera.widht"], "--unset camera.widht: [camera] has no key 'widht'"),
        (["--unset", "hair.source"], "--unset hair.source: hair.source is required"),
        (
            ["--set", "camera.width=3", "--unset", "camera.width"],
            "--set camera.width=… and --unset camera.width",
        ),
        (["--set", "shading.kd=-1"], "--set shading.kd=-1: shading.kd must be"),
        (["--set", "camra.width=3"], "--set camra.width=3: no table [camra]"),
        (["--size", "20000"], "--size 20000: camera.width must be an integer in [1, 16384]"),
        (["--set", "camera.fov=0"], "--set camera.fov=0: camera.fov must be in (0, 180)"),
    ],
)
def test_errors_from_the_command_line_name_the_option(scene_file, options, message, capsys):
    assert main(["render", str(scene_file), *options, "-o", "x.exr"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"hairjax: error: {message}" or err.startswith(f"hairjax: error: {message}"), err
    assert len(err.splitlines()) == 1 and str(scene_file) not in err


def test_an_error_in_the_file_still_names_the_file(scene_file, capsys):
    scene_file.write_text(SCENE.replace("width = 40", "width = 0"))
    assert main(["render", str(scene_file), "--set", "shading.kd=0.3", "-o", "x.exr"]) == 2
    assert capsys.readouterr().err.startswith(f"hairjax: error: {scene_file}: camera.width")
