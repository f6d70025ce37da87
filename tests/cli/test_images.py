"""Images on the command line: a damaged target, view input or mask is refused in one
line naming the file (exit 2, nothing from the decoders on stdout or stderr); `fit --mask`
weights a target's pixels (docs/fitting.md, "Target images and masks"); an RGBA target
fits as the same image saved RGB; `compare --diff` writes the renders' difference and a
verdict. Files are written by OpenImageIO's writers, the targets rendered here."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import OpenImageIO as oiio
import pytest

import hairjax as hj
from hairjax.cli import main

TINY_SCENE = """
[hair]
source = "furball"
strands = 30
points = 5
[camera]
width = 24
height = 18
[shadows]
maps = 4
resolution = 16
[shading]
shininess = 20.0
kappa = 0.8
ambient = 0.05
"""
# The targets' parameters: the scene's, but for Kd and Ks (fitted from its 0.6 and 0.3).
TRUE = hj.ShadingParams(kd=(0.3, 0.5, 0.2), ks=0.4, shininess=20.0, kappa=0.8, ambient=0.05)


@pytest.fixture
def scene_file(tmp_path):
    path = tmp_path / "tiny.toml"
    path.write_text(TINY_SCENE)
    return path


def oiio_write(path, data: np.ndarray, fmt: str):
    h, w, c = data.shape
    spec = oiio.ImageSpec(w, h, c, fmt)
    spec.attribute("oiio:UnassociatedAlpha", 1)  # colour stored as given beside alpha
    out = oiio.ImageOutput.create(str(path))
    assert out is not None and out.open(str(path), spec), oiio.geterror()
    assert out.write_image(np.ascontiguousarray(data)) and out.close()
    return path


def truncated(tmp_path, suffix: str, shape=(18, 24)):
    """An image of `shape` written whole by OpenImageIO, then cut to two thirds."""
    image = np.random.default_rng(0).uniform(0.0, 1.0, (*shape, 3)).astype(np.float32)
    if suffix == ".exr":
        whole = oiio_write(tmp_path / "whole.exr", image, "half")
    else:
        whole = oiio_write(tmp_path / "whole.png", np.round(image * 255).astype(np.uint8), "uint8")
    path = tmp_path / f"cut{suffix}"
    data = whole.read_bytes()
    path.write_bytes(data[: len(data) * 2 // 3])
    return path


def assert_one_line_naming(captured, path):
    assert captured.out == ""
    lines = captured.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"hairjax: error: {path}: cannot read: "), lines


# --------------------------------------------------------------------------- damaged inputs


@pytest.mark.parametrize("suffix", [".exr", ".png"])
def test_fit_refuses_a_truncated_target(scene_file, tmp_path, capfd, suffix):
    """On main this fitted zeros for the missing rows and could exit 0, "converged"."""
    target = truncated(tmp_path, suffix)
    out = tmp_path / "fit.json"
    assert main(["fit", str(scene_file), "--target", str(target), "--json", str(out)]) == 2
    assert_one_line_naming(capfd.readouterr(), target)
    assert not out.exists()


@pytest.mark.parametrize("option", ["--mask", "--holdout"])
def test_fit_refuses_a_truncated_mask_or_holdout(scene_file, tmp_path, capfd, option):
    target = oiio_write(tmp_path / "t.exr", np.full((18, 24, 3), 0.5, np.float32), "float")
    damaged = truncated(tmp_path, ".png")
    assert main(["fit", str(scene_file), "--target", str(target), option, str(damaged)]) == 2
    assert_one_line_naming(capfd.readouterr(), damaged)


@pytest.mark.parametrize("suffix", [".exr", ".png"])
def test_view_refuses_a_truncated_image(tmp_path, capfd, suffix):
    image = truncated(tmp_path, suffix)
    out = tmp_path / "shown.png"
    assert main(["view", str(image), "-o", str(out)]) == 2
    assert_one_line_naming(capfd.readouterr(), image)
    assert not out.exists()


def test_view_of_a_truncated_exr_prints_nothing_else_up_to_exit(tmp_path):
    """A whole process: OpenImageIO printed an unread error to stdout when its buffer was
    destroyed, after the command had finished."""
    image = truncated(tmp_path, ".exr")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    run = subprocess.run(
        [
            sys.executable,
            "-c",
            "import sys; from hairjax.cli import main; sys.exit(main())",
            "view",
            str(image),
        ],
        capture_output=True,
        text=True,
        env=env,
    )
    assert run.returncode == 2 and run.stdout == ""
    assert run.stderr.startswith(f"hairjax: error: {image}: cannot read: ") and run.stderr.count("\n") == 1


# --------------------------------------------------------------------------- fit --mask


def fitted(scene_file, tmp_path, target, *extra) -> dict:
    """`hairjax fit --fit kd,ks` (one linear solve: the gains are solved for, docs/fitting.md)
    and its JSON's fitted parameters."""
    out = tmp_path / "fit.json"
    argv = ["fit", str(scene_file), "--target", str(target), "--fit", "kd,ks", "--json", str(out), "-q"]
    assert main([*argv, *extra]) == 0
    return json.loads(out.read_text())["params"]


def test_a_mask_hides_what_it_covers(scene_file, tmp_path, capsys):
    """The target is the scene rendered with known Kd and Ks, its right half painted
    white (a lamp in the photograph). Unmasked, the fit chases the white; with a mask that
    is 0 over the painted half it recovers Kd and Ks as from the clean image."""
    scene = hj.load_scene(scene_file)
    image = np.asarray(hj.render(scene, TRUE), np.float32)[..., :3].copy()
    image[:, 12:] = 1.0
    target = oiio_write(tmp_path / "t.exr", image, "float")
    matte = np.full((18, 24, 1), 255, np.uint8)
    matte[:, 12:] = 0
    mask = oiio_write(tmp_path / "matte.png", matte, "uint8")

    plain = fitted(scene_file, tmp_path, target)
    masked = fitted(scene_file, tmp_path, target, "--mask", str(mask))
    # The left half is the render's own pixels (float32 EXR): recovery to float32 rounding
    # through a linear solve, where the white half moves Kd by far more than 1e-3.
    np.testing.assert_allclose(masked["kd"], TRUE.kd, rtol=1e-3)
    np.testing.assert_allclose(masked["ks"], TRUE.ks, rtol=1e-3)
    assert np.max(np.abs(np.asarray(plain["kd"]) - TRUE.kd)) > 0.05


def test_a_mask_of_another_size_is_refused_naming_both(scene_file, tmp_path, capsys):
    target = oiio_write(tmp_path / "t.exr", np.full((18, 24, 3), 0.5, np.float32), "float")
    mask = oiio_write(tmp_path / "m.png", np.full((18, 20, 1), 255, np.uint8), "uint8")
    assert main(["fit", str(scene_file), "--target", str(target), "--mask", str(mask)]) == 2
    err = capsys.readouterr().err
    assert err == f"hairjax: error: {mask}: the mask is 20x18 but its target {target} is 24x18\n"


def test_more_masks_than_targets_is_refused(scene_file, tmp_path, capsys):
    target = oiio_write(tmp_path / "t.exr", np.full((18, 24, 3), 0.5, np.float32), "float")
    mask = oiio_write(tmp_path / "m.png", np.full((18, 24, 1), 255, np.uint8), "uint8")
    argv = ["fit", str(scene_file), "--target", str(target), "--mask", str(mask), "--mask", str(mask)]
    assert main(argv) == 2
    assert "2 --mask for 1 --target" in capsys.readouterr().err


def test_an_rgba_target_fits_as_the_same_image_saved_rgb(scene_file, tmp_path):
    """8-bit PNG targets of one render, one with the render's coverage as alpha: the fit
    sees the same colour in both (on main the RGBA one was premultiplied on read)."""
    scene = hj.load_scene(scene_file)
    image = np.asarray(hj.render(scene, TRUE), np.float64)
    encoded = np.round(np.clip(image, 0, 1) ** (1 / 2.2) * 255).astype(np.uint8)  # any codes do
    rgb = oiio_write(tmp_path / "rgb.png", encoded[..., :3], "uint8")
    rgba = oiio_write(tmp_path / "rgba.png", encoded, "uint8")
    assert 0 < np.count_nonzero(encoded[..., 3] < 255)  # some pixels partly covered
    assert fitted(scene_file, tmp_path, rgb) == fitted(scene_file, tmp_path, rgba)


# --------------------------------------------------------------------------- compare --diff


def test_compare_writes_its_difference_and_a_verdict(gl, scene_file, tmp_path, capsys):
    diff, report = tmp_path / "d.png", tmp_path / "c.json"
    argv = ["compare", str(scene_file), "--repeats", "1", "--diff", str(diff), "--json", str(report)]
    assert main(argv) == 0
    out = capsys.readouterr().out
    verdict = [line for line in out.splitlines() if line.startswith("  verdict")]
    assert len(verdict) == 1 and "within band" in verdict[0]
    assert f"wrote {diff}" in out
    data = json.loads(report.read_text())
    assert data["outside_band"] == 0 and 0 <= data["band_share"] < 1
    assert hj.read_image(diff).shape == (18, 24, 3)


@pytest.mark.parametrize(
    "name, message",
    [("d.jpg", "(--diff): unsupported extension '.jpg'; use .exr or .png"), ("folder.png", "is a directory")],
)
def test_compare_checks_its_diff_path_before_work(scene_file, tmp_path, capsys, monkeypatch, name, message):
    from hairjax import tools

    monkeypatch.setattr(tools, "compare", lambda *a, **k: pytest.fail("compared before checking --diff"))
    (tmp_path / "folder.png").mkdir()
    argv = ["compare", str(scene_file), "--json", str(tmp_path / "c.json"), "--diff", str(tmp_path / name)]
    assert main(argv) == 2
    assert message in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["folder.png", "tiny.toml"]


def test_compare_that_fails_leaves_no_diff(scene_file, tmp_path, capsys, monkeypatch):
    from hairjax.tools import _compare

    def broken(*args, **kwargs):
        raise ValueError("the timings failed")

    monkeypatch.setattr(_compare, "median_time", broken)  # after the diff is written
    assert main(["compare", str(scene_file), "--diff", str(tmp_path / "d.png")]) == 2
    assert "the timings failed" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["tiny.toml"]
