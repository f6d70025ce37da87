"""`hairjax.reference_image` and `hairjax reference`: the image's form and determinism, the
refused features, a missing Mitsuba, and the sampler's count. The tests that render skip,
with the reason, only where Mitsuba (the [reference] extra) is not installed; the refusals
and the missing-Mitsuba message are tested everywhere."""

from __future__ import annotations

import datetime
import importlib.metadata
import importlib.util
import json
import re
import sys

import numpy as np
import PIL.Image
import pytest

import hairjax as hj
from hairjax._errors import MissingDependency, SceneError
from hairjax._reference._mitsuba_scene import sample_count
from hairjax.cli import main

NEEDS_MITSUBA = pytest.mark.skipif(
    importlib.util.find_spec("mitsuba") is None,
    reason="the [reference] extra is not installed: pip install 'hairjax[reference]'",
)
SCENE_TEXT = """
[hair]
source = "furball"
strands = 30
points = 4
width = 2.0

[camera]
eye = [0.0, 0.0, 3.5]
width = 24
height = 16

[background]
color = [0.1, 0.2, 0.3]

[reference]
eumelanin = 0.3
max_depth = 3
spp = 4
"""


def _scene(tmp_path, extra=""):
    path = tmp_path / "scene.toml"
    path.write_text(SCENE_TEXT + extra)
    return path


@NEEDS_MITSUBA
def test_the_image_is_rgba_over_the_background_and_the_same_for_a_seed(tmp_path):
    scene = hj.load_scene(_scene(tmp_path))
    image = hj.reference_image(scene, seed=7)
    assert image.shape == (16, 24, 4) and image.dtype == np.float32
    alpha = image[..., 3]
    assert 0.05 < alpha.mean() < 0.95 and alpha.min() >= 0 and alpha.max() <= 1
    empty = alpha == 0
    np.testing.assert_array_equal(
        image[empty, :3], np.broadcast_to(np.float32([0.1, 0.2, 0.3]), (empty.sum(), 3))
    )
    np.testing.assert_array_equal(hj.reference_image(scene, seed=7), image)
    assert not np.array_equal(hj.reference_image(scene, seed=8), image)


@NEEDS_MITSUBA
def test_the_sampler_takes_the_count_reported():
    import mitsuba as mi

    from hairjax._reference._render import _variant

    with _variant(mi):
        for spp in (1, 2, 16, 32, 48, 64, 100, 128):
            sampler = mi.load_dict({"type": "multijitter", "sample_count": spp})
            assert sampler.sample_count() == sample_count(spp), spp


def test_sample_count_keeps_square_grids():
    assert [sample_count(n) for n in (1, 4, 16, 32, 48, 64, 256)] == [1, 4, 16, 35, 48, 64, 256]


@NEEDS_MITSUBA
def test_the_command_writes_the_exr(tmp_path, capsys):
    out = tmp_path / "ref.exr"
    assert main(["reference", str(_scene(tmp_path)), "--spp", "2", "--sample-seed", "3", "-o", str(out)]) == 0
    text = capsys.readouterr()
    assert "note: hair.width is in pixels" in text.err
    assert "24x16, 2 spp, seed 3, max_depth 3" in text.out
    image = hj.read_image(out)
    scene = hj.load_scene(_scene(tmp_path))
    np.testing.assert_array_equal(image, hj.reference_image(scene, spp=2, seed=3))
    assert f"wrote {out.with_suffix('.json')}" in text.out


@NEEDS_MITSUBA
def test_the_sidecar_records_what_made_the_image(tmp_path, monkeypatch, capsys):
    """Beside the image: the scene's pigments (eumelanin from its [reference] table,
    pheomelanin Mitsuba's default 0.2), the spp the sampler took, the seed, the versions of
    Mitsuba and hairjax as installed, the time and the command."""
    out = tmp_path / "ref.exr"
    argv = ["reference", str(_scene(tmp_path)), "--spp", "2", "--sample-seed", "3", "-o", str(out)]
    argv += ["--set", "camera.fov=35"]
    monkeypatch.setattr(sys, "argv", ["hairjax", *argv])  # the record's command is the process's
    assert main(argv) == 0
    record = json.loads(out.with_suffix(".json").read_text())
    reference = record["reference"]
    assert (reference["eumelanin"], reference["pheomelanin"], reference["sigma_a"]) == (0.3, 0.2, None)
    assert (reference["spp"], reference["sample_seed"], reference["max_depth"]) == (2, 3, 3)
    assert record["versions"]["mitsuba"] == importlib.metadata.version("mitsuba")
    assert record["versions"]["hairjax"] == importlib.metadata.version("hairjax")
    assert record["overrides"] == {"camera.fov": 35}
    assert record["scene"]["camera"]["fov"] == 35 and record["scene"]["strands"]["type"] == "Strands"
    assert record["image"] == {"files": ["ref.exr"], "width": 24, "height": 16}
    assert record["command"] == ["hairjax", *argv]
    assert record["timings_s"]["reference"] > 0
    created = datetime.datetime.fromisoformat(record["created"])
    assert abs(datetime.datetime.now(datetime.UTC) - created) < datetime.timedelta(minutes=5)


@NEEDS_MITSUBA
def test_png_alone_and_beside_the_exr(tmp_path, capsys):
    """--png alone writes the PNG and its sidecar; with -o the sidecar is the EXR's, and the
    PNG is the EXR's pixels in 8-bit sRGB."""
    scene = str(_scene(tmp_path))
    png = tmp_path / "alone.png"
    assert main(["reference", scene, "--spp", "1", "--png", str(png), "-q"]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["alone.json", "alone.png", "scene.toml"]
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    exr, both = tmp_path / "both.exr", tmp_path / "both.png"
    assert main(["reference", scene, "--spp", "1", "-o", str(exr), "--png", str(both), "-q"]) == 0
    assert json.loads((tmp_path / "both.json").read_text())["image"]["files"] == ["both.exr", "both.png"]
    linear = np.clip(hj.read_image(exr)[..., :3], 0, 1)
    # sRGB's encoding (IEC 61966-2-1), to compare with the PNG's 8-bit codes: half a code apart.
    srgb = np.where(linear <= 0.0031308, 12.92 * linear, 1.055 * linear ** (1 / 2.4) - 0.055)
    codes = np.asarray(PIL.Image.open(both).convert("RGB"), dtype=np.float64)
    assert np.abs(codes - srgb * 255).max() <= 0.5 + 1e-6


@NEEDS_MITSUBA
def test_no_sidecar(tmp_path, capsys):
    out = tmp_path / "ref.exr"
    assert main(["reference", str(_scene(tmp_path)), "--spp", "1", "-o", str(out), "--no-sidecar"]) == 0
    assert not out.with_suffix(".json").exists() and out.exists()


@pytest.mark.parametrize(
    ("options", "named"),
    [
        (["--png", "r.exr"], r"r\.exr \(--png\): unsupported extension '\.exr'; use \.png"),
        (["-o", "r.png", "--png", "r.png"], r"r\.png: named by both -o and --png"),
        (["-o", "r.exr", "--png", "r.json"], r"r\.json \(--png\): unsupported extension"),
    ],
    ids=["png-as-exr", "same-file", "png-as-json"],
)
def test_bad_images_are_refused_before_the_work(tmp_path, monkeypatch, capsys, options, named):
    def never(*args, **kwargs):
        raise AssertionError("the scene was read before the outputs were checked")

    monkeypatch.setattr("hairjax.cli._scenes.load_cli_scene", never)
    monkeypatch.chdir(tmp_path)
    line = _one_line_error(capsys, ["reference", *options])
    assert re.search(named, line), line
    assert list(tmp_path.iterdir()) == []


def test_the_sidecar_of_the_default_output_is_checked_first(tmp_path, monkeypatch, capsys):
    """The sidecar is an output like the image: a folder in its place is refused before the work."""
    monkeypatch.setattr("hairjax.cli._scenes.load_cli_scene", lambda *a: pytest.fail("work started"))
    (tmp_path / "r.json").mkdir()
    line = _one_line_error(capsys, ["reference", "-o", str(tmp_path / "r.exr")])
    assert "r.json (the sidecar (--no-sidecar: none)): is a directory" in line, line


def _one_line_error(capsys, argv):
    code = main(argv)
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


def test_a_missing_mitsuba_is_one_line_naming_the_extra(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "mitsuba", None)  # `import mitsuba` raises ImportError
    line = _one_line_error(capsys, ["reference", str(_scene(tmp_path)), "-o", str(tmp_path / "r.exr")])
    assert "pip install 'hairjax[reference]'" in line
    with pytest.raises(MissingDependency, match=r"pip install 'hairjax\[reference\]'"):
        hj.reference_image(hj.load_scene(_scene(tmp_path)))
    assert not (tmp_path / "r.exr").exists()


@pytest.mark.parametrize(
    ("extra", "overrides", "feature"),
    [
        ("\n[streaks]\n", [], r"\[streaks\]"),
        (
            "",
            ["--set", "hair.geometry=patches", "--set", "hair.patch_width=0.05"],
            "hair.geometry = 'patches'",
        ),
    ],
    ids=["streaks", "patches"],
)
def test_an_unsupported_feature_is_one_line_naming_it(
    tmp_path, monkeypatch, capsys, extra, overrides, feature
):
    monkeypatch.setattr("hairjax._reference._support.import_mitsuba", lambda: None)  # present or not
    line = _one_line_error(
        capsys, ["reference", str(_scene(tmp_path, extra)), *overrides, "-o", str(tmp_path / "r.exr")]
    )
    assert re.search(feature, line), line


def test_the_api_refuses_before_importing_mitsuba(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "mitsuba", None)
    scene = hj.load_scene(_scene(tmp_path, "\n[streaks]\n"))
    with pytest.raises(SceneError, match=r"\[streaks\]"):
        hj.reference_image(scene)
    plain = hj.load_scene(_scene(tmp_path))
    shifted = plain.replace(camera=hj.Camera(eye=(0, 0, 3.5), width=24, height=16, offset=(0.25, 0.0)))
    with pytest.raises(SceneError, match=r"camera\.offset"):
        hj.reference_image(shifted)
    for spp, seed in ((0, 0), (4, -1), (4, 2**32)):
        with pytest.raises(ValueError, match="spp|seed"):
            hj.reference_image(plain, spp=spp, seed=seed)


def test_a_bad_sample_seed_is_refused_before_the_scene_is_read(tmp_path, monkeypatch, capsys):
    def never(*args, **kwargs):
        raise AssertionError("the scene was read before --sample-seed was checked")

    monkeypatch.setattr("hairjax.cli._scenes.load_cli_scene", never)
    line = _one_line_error(capsys, ["reference", "--sample-seed", "-1", "-o", str(tmp_path / "r.exr")])
    assert re.search(r"seed must be an integer in \[0, 4294967295\], got -1", line), line
