"""A seeded fuzz of the command line over corrupted hair files, images and scenes.

Each case corrupts a valid input (truncation, flipped bytes, a header field or a scene key
set to an extreme or ill-typed value) and runs one command in process. Whatever the input,
the command must end in one of the documented ways (README, "Exit codes"): 0 with a finite
result, or 2 (bad input) / 3 (a fit that did not converge) with one line on stderr, never a
traceback or an unexpected error (exit 1), and on failure no output file left behind.

The cases are drawn from fixed seeds, so a failure names a case that reruns identically.
"""

from __future__ import annotations

import os
import struct

import numpy as np
import pytest
from helpers import DATA

import hairjax as hj
from hairjax.cli import main

# Exit codes the README documents for a command that did not crash: done, bad input, fit
# not converged. 1 (unexpected error) and a raised exception are the failures looked for.
DOCUMENTED = {0, 2, 3}
CASES = 16  # per input kind; with the tiny sizes below the whole module runs in ~30 s

TINY_SCENE = """
[hair]
source = "furball"
strands = 40
points = 5
seed = 1
[camera]
width = 24
height = 20
[shading]
model = "kajiya-kay"
kd = [0.5, 0.3, 0.2]
ks = 0.3
shininess = 20.0
kappa = 1.0
[shadows]
method = "opacity-maps"
maps = 4
resolution = 16
[ordering]
method = "bins"
bins = 16
"""

# Scene keys and the values a fuzzed scene gives them: extremes, wrong types, non-finite.
SCENE_KEYS = [
    "hair.strands",
    "hair.points",
    "hair.length",
    "hair.alpha",
    "hair.width",
    "camera.width",
    "camera.fov",
    "camera.eye",
    "light.direction",
    "shading.kd",
    "shading.shininess",
    "shading.kappa",
    "shadows.maps",
    "shadows.resolution",
    "ordering.bins",
]
EXTREMES = [
    "0",
    "-1",
    "1e9",
    "1e39",
    "-1e-300",
    "nan",
    "inf",
    '"text"',
    "[]",
    "[1e30, 0, 0]",
    "[0.0, 0.0, 0.0]",
    "true",
    "{ a = 1 }",
    "0.5",
    "16384",
    "1e6",
]


def _run(argv, capfd) -> tuple[int, str]:
    """Run one command; the exit code and stderr, after the checks every case shares.
    `capfd` reads the process's file descriptors, so a message that a C or C++ library
    prints (OpenImageIO's, numpy's) is seen too."""
    code = main(argv)
    captured = capfd.readouterr()
    assert code in DOCUMENTED, f"exit {code}: {captured.err}"
    stray = [line for line in captured.err.splitlines() if not line.startswith("hairjax: ")]
    assert stray == [], captured.err  # no traceback, no library's message
    if argv[0] in ("render", "view"):  # quiet (-q): their results are files, not text
        assert captured.out == "", captured.out
    if code != 0:
        errors = [line for line in captured.err.splitlines() if line.startswith("hairjax: error")]
        assert len(errors) == 1, captured.err  # one line naming the problem
    return code, captured.err


def _left_behind(folder, expected) -> list[str]:
    """Files in `folder` other than `expected`: a temporary or a half-written output."""
    return sorted(set(os.listdir(folder)) - set(expected))


def _check_render(tmp_path, argv, capfd) -> None:
    """Render to out/; a success must be finite, a failure must leave out/ empty."""
    out = tmp_path / "out"
    out.mkdir()
    code, err = _run([*argv, "-o", str(out / "a.exr"), "-q"], capfd)
    if code == 0:
        image = hj.read_image(out / "a.exr")
        assert np.isfinite(image).all(), err
        # Every model term and the backdrop are non-negative for inputs in their ranges.
        assert image.min() >= 0, err
        assert _left_behind(out, ["a.exr", "a.json"]) == []
    else:
        assert _left_behind(out, []) == [], err


def _corrupt(data: bytes, kind: int, rng: np.random.Generator) -> tuple[bytes, bool]:
    """Corruption number `kind` of `data`, and whether it is a truncation (which no reader may accept):
    truncated, bytes flipped, a 4-byte field overwritten with an extreme integer or float,
    or garbage appended."""
    data = bytearray(data)
    if kind == 0:
        return bytes(data[: rng.integers(0, len(data))]), True
    if kind == 1:
        for i in rng.integers(0, len(data), size=rng.integers(1, 8)):
            data[i] ^= int(rng.integers(1, 256))
        return bytes(data), False
    if kind == 2:
        at = int(rng.integers(0, max(len(data) - 4, 1)))
        field = rng.choice(
            [
                struct.pack("<I", 0xFFFFFFFF),
                struct.pack("<I", 0),
                struct.pack("<f", float("nan")),
                struct.pack("<f", -3.0e38),
                struct.pack("<f", -2.0),
            ]
        )
        data[at : at + 4] = field
        return bytes(data), False
    garbage = rng.integers(0, 256, size=int(rng.integers(1, 64)), dtype=np.uint8)
    return bytes(data) + bytes(garbage), False


HAIR_FILES = [
    DATA / "hair" / "Bangs_100.hair",
    DATA / "hair" / "Curly_100.ply",
    DATA / "tressfx" / "ponytail_tail.tfx",
]


@pytest.mark.parametrize("case", range(CASES))
def test_corrupted_hair_file(case, tmp_path, capfd):
    rng = np.random.default_rng(1000 + case)
    source = HAIR_FILES[case // 4 % len(HAIR_FILES)]
    broken = tmp_path / f"broken{source.suffix}"
    data, truncated = _corrupt(source.read_bytes(), case % 4, rng)
    broken.write_bytes(data)
    code, err = _run(["info", str(broken)], capfd)
    assert not (truncated and code == 0), "a truncated hair file was read"
    _check_render(tmp_path, ["render", str(broken), "--size", "24"], capfd)


@pytest.mark.parametrize("case", range(CASES))
def test_fuzzed_scene(case, tmp_path, capfd):
    rng = np.random.default_rng(2000 + case)
    lines = TINY_SCENE.strip().splitlines()
    overrides = []
    for _ in range(int(rng.integers(1, 3))):
        overrides += ["--set", f"{rng.choice(SCENE_KEYS)}={rng.choice(EXTREMES)}"]
    text = "\n".join(lines)
    if case % 4 == 0:  # a torn file, cut anywhere
        text = text[: rng.integers(1, len(text))]
    scene = tmp_path / "scene.toml"
    scene.write_text(text)
    _check_render(tmp_path, ["render", str(scene), *overrides], capfd)


def _target(tmp_path, suffix: str):
    """A small target image of TINY_SCENE, written by OpenImageIO through hairjax."""
    scene = tmp_path / "scene.toml"
    scene.write_text(TINY_SCENE)
    target = tmp_path / f"target{suffix}"
    hj.write_image(target, np.asarray(hj.render(hj.load_scene(scene))))
    return scene, target


@pytest.mark.parametrize("case", range(CASES))
def test_corrupted_image(case, tmp_path, capfd):
    rng = np.random.default_rng(3000 + case)
    scene, target = _target(tmp_path, [".exr", ".png"][case // 4 % 2])
    broken = tmp_path / f"broken{target.suffix}"
    data, truncated = _corrupt(target.read_bytes(), case % 4, rng)
    broken.write_bytes(data)
    out = tmp_path / "out"
    out.mkdir()
    code, err = _run(["view", str(broken), "-o", str(out / "v.png"), "-q"], capfd)
    assert not (truncated and code == 0), "a truncated image was read"
    assert _left_behind(out, ["v.png"] if code == 0 else []) == [], err
    argv = ["fit", str(scene), "--target", str(broken), "--fit", "ks", "--max-steps", "5", "-q"]
    code, err = _run([*argv, "--json", str(out / "fit.json")], capfd)
    assert not (truncated and code == 0), "a truncated target was fitted"
    expected = ["v.png", "fit.json"] if code in (0, 3) else ["v.png"]
    assert _left_behind(out, expected) == [], err
