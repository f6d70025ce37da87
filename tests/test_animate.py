"""The animated fur ball (docs/model.md §15): the path's second derivative against finite
differences, the direction hairs bend, the frames `hairjax animate` writes, its errors."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from helpers import unexplained_pixels

import hairjax as hj
from hairjax._animate import (
    Motion,
    inertia_vector,
    load_animation,
    path_acceleration,
    path_position,
    write_frames,
)
from hairjax._errors import SceneError
from hairjax.cli import main

SCENE = """
[hair]
source = "furball"
strands = 40
points = 5
translate = [0.1, 0.0, 0.0]
[camera]
width = 24
height = 20
[shadows]
method = "none"
[animation]
amplitude = [0.5, 0.2, 0.1]
frequency = [1.0, 2.0, 3.0]
phase = [0.0, 30.0, 90.0]
inertia = 0.01
frames = 3
"""


@pytest.fixture
def scene_file(tmp_path):
    path = tmp_path / "anim.toml"
    path.write_text(SCENE)
    return path


def test_acceleration_is_the_paths_second_difference():
    motion = Motion(amplitude=(0.5, 0.2, 0.1), frequency=(1.0, 2.0, 3.0), phase=(0.0, 30.0, 90.0))
    h = 1e-4
    for t in (0.0, 0.13, 0.5, 0.91):
        fd = (
            path_position(motion, t + h) - 2 * path_position(motion, t) + path_position(motion, t - h)
        ) / h**2
        # Truncation h²/12·|p''''| ≤ 1e-8/12·0.1·(6π)⁴ ≈ 1e-5; roundoff ~4e-16/h² = 4e-8.
        np.testing.assert_allclose(path_acceleration(motion, t), fd, atol=2e-5)
    # The values by hand at t = 0: p'' = −a (2πf)² sin φ.
    expected = -np.array([0.0, 0.2 * (4 * np.pi) ** 2 * 0.5, 0.1 * (6 * np.pi) ** 2])
    np.testing.assert_allclose(path_acceleration(motion, 0.0), expected, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(
        inertia_vector(Motion(inertia=0.25), 0.3), -0.25 * path_acceleration(Motion(), 0.3), rtol=1e-15
    )


def test_hairs_bend_away_from_the_acceleration(scene_file):
    """In the ball's frame a hair feels −m·p'' (the seed's inertia term with d'Alembert's
    sign): its tip moves against the acceleration, and the roots follow the path."""
    animation = load_animation(scene_file)
    still = dataclasses.replace(animation, motion=dataclasses.replace(animation.motion, inertia=0.0))
    for t in (0.1, 0.35, 0.8):
        moving, resting = animation.scene(t).strands, still.scene(t).strands
        roots = moving.points[moving.offsets[:-1]]
        np.testing.assert_allclose(
            roots,
            np.broadcast_to(np.add((0.1, 0.0, 0.0), path_position(animation.motion, t)), roots.shape),
            atol=1e-12,
        )
        tips = moving.offsets[1:] - 1
        shift = (moving.points[tips] - resting.points[tips]).mean(axis=0)
        accel = path_acceleration(animation.motion, t)
        cosine = shift @ accel / (np.linalg.norm(shift) * np.linalg.norm(accel))
        assert cosine < -0.9, (t, cosine)


def test_frames_are_written_and_numbered(scene_file, tmp_path):
    out = tmp_path / "frames"
    written = write_frames(load_animation(scene_file), out, png=True, gif=True)
    names = sorted(p.name for p in out.iterdir())
    assert names == [
        "animation.gif",
        "frame_0000.exr",
        "frame_0000.png",
        "frame_0001.exr",
        "frame_0001.png",
        "frame_0002.exr",
        "frame_0002.png",
    ]  # no temp files left
    assert sorted(p.name for p in written) == names
    # Frame k is the still scene at t = k/3, rendered.
    scene = load_animation(scene_file).scene(1 / 3)
    np.testing.assert_allclose(
        hj.read_image(out / "frame_0001.exr"), np.asarray(hj.render(scene), np.float32), atol=1e-6
    )
    from PIL import Image

    with Image.open(out / "animation.gif") as gif:
        assert gif.n_frames == 3 and gif.size == (24, 20)


def test_cli_animate_and_its_errors(scene_file, tmp_path, capsys, gl):
    out = tmp_path / "cli"
    assert main(["animate", str(scene_file), "--frames", "2", "-o", str(out), "--backend", "gl"]) == 0
    assert "wrote 2 frames" in capsys.readouterr().out
    assert sorted(p.name for p in out.iterdir()) == ["frame_0000.exr", "frame_0001.exr"]
    # GL's frame is the JAX renderer's frame (to PIXEL_TOL outside the camera band, as
    # tests/gl/test_renderer.py; this scene has no shadows).
    scene = load_animation(scene_file).scene(1 / 2)
    bad, _ = unexplained_pixels(scene, hj.read_image(out / "frame_0001.exr"), np.asarray(hj.render(scene)))
    assert bad.size == 0

    with pytest.raises(SystemExit) as refused:  # argparse: refused before anything is read
        main(["animate", str(scene_file), "--frames", "0", "-o", str(out)])
    assert refused.value.code == 2
    assert "argument --frames: expected a positive integer, got '0'" in capsys.readouterr().err
    a_file = tmp_path / "file"
    a_file.write_text("")
    assert main(["animate", str(scene_file), "-o", str(a_file)]) == 2
    assert "is a file; -o takes a folder" in capsys.readouterr().err
    scalp = tmp_path / "scalp.toml"
    scalp.write_text('[hair]\nsource = "scalp"\nstrands = 3\n')
    assert main(["animate", str(scalp), "-o", str(out)]) == 2
    assert "hair.source must be 'furball' to animate" in capsys.readouterr().err


@pytest.mark.parametrize(
    "text, message",
    [
        ("frames = 0", r"animation\.frames must be an integer >= 1, got 0"),
        ("inertia = -1", r"animation\.inertia must be >= 0, got -1"),
        ("amplitude = [1, 2]", r"animation\.amplitude must be an array of 3 finite numbers"),
        ("speed = 2", r"unknown key animation\.speed"),
    ],
)
def test_animation_table_errors_name_the_key(tmp_path, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(f'[hair]\nsource = "furball"\nstrands = 3\n[animation]\n{text}\n')
    with pytest.raises(SceneError, match=f"^{path}: {message}"):
        load_animation(path)
