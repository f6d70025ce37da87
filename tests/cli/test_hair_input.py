"""Hair files through the command line: the new formats render and show in `info`,
unknown suffixes and out-of-range data are one line and exit 2, dropped strands one
warning line, and no numpy warning reaches the user."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from hairjax.cli import main

KNOWN = ".hair, .tfx, .ply, .data, .usd, .usda, .usdc, .usdz"


def data_file(path, strands):
    """USC-HairSalon .data: i32 strand count, per strand an i32 vertex count and its f32 xyz."""
    body = struct.pack("<i", len(strands))
    for s in strands:
        body += struct.pack("<i", len(s)) + np.asarray(s, "<f4").tobytes()
    path.write_bytes(body)
    return path


def hair_file(path, strands, color):
    """Cem Yuksel's HAIR with segments, points and colour arrays."""
    n_points = sum(len(s) for s in strands)
    header = struct.pack("<4sIIIIff3f", b"HAIR", len(strands), n_points, 1 | 2 | 16, 0, 1, 0, 1, 1, 1)
    body = struct.pack(f"<{len(strands)}H", *[len(s) - 1 for s in strands])
    body += np.concatenate(strands).astype("<f4").tobytes() + np.asarray(color, "<f4").tobytes()
    path.write_bytes(header + bytes(88) + body)
    return path


def strands(scale=1.0):
    rng = np.random.default_rng(5)
    return [scale * np.cumsum(rng.normal(scale=0.2, size=(6, 3)), axis=0) for _ in range(12)]


def one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    return lines[0]


@pytest.mark.parametrize("command", ["render", "info"])
def test_unknown_file_type_is_one_line(tmp_path, capsys, command):
    path = tmp_path / "hair.xyz"
    path.write_bytes(b"\xff\xfe not a scene")
    assert main([command, str(path)]) == 2
    line = one_line(capsys.readouterr().err)
    assert line.startswith(f"hairjax: error: {path}: unknown file type '.xyz' (known: ")
    assert line.endswith(f"{KNOWN})") and "UTF-8" not in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["hair.xyz"]


@pytest.mark.parametrize("command", ["render", "info"])
def test_negative_colour_is_one_line(tmp_path, capsys, command):
    color = np.full((72, 3), 0.5)
    color[9] = [0.5, -2.0, 0.5]
    path = hair_file(tmp_path / "neg.hair", strands(), color)
    assert (
        main(
            [command, str(path), "-o", str(tmp_path / "x.exr")]
            if command == "render"
            else [command, str(path)]
        )
        == 2
    )
    assert "the colour of point 9 is (0.5, -2, 0.5)" in one_line(capsys.readouterr().err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["neg.hair"]


def test_far_coordinates_are_one_line(tmp_path, capsys):
    path = data_file(tmp_path / "far.data", strands(scale=3e37))
    assert main(["render", str(path), "-o", str(tmp_path / "x.exr")]) == 2
    line = one_line(capsys.readouterr().err)
    assert f"{path}: point" in line and "lies beyond ±1e+18" in line and "overflow" not in line


def test_info_on_the_new_formats(tmp_path, capsys):
    path = data_file(tmp_path / "s.data", strands())
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "format           USC-HairSalon\n" in out and "strands          12\n" in out


def test_render_a_data_file_near_the_bound(tmp_path, capsys):
    """Coordinates of order 1e17 (under the 1e18 bound) render with no numpy warning; a
    one-point strand is dropped with one warning line. Every stderr line is accounted for."""
    hair = strands(scale=1e17) + [np.array([[0.0, 0.0, 0.0]])]
    path = data_file(tmp_path / "big.data", hair)
    out = tmp_path / "big.exr"
    assert main(["render", str(path), "--size", "16", "-o", str(out), "-q"]) == 0
    err = capsys.readouterr().err
    assert err.strip().splitlines() == [
        f"hairjax: warning: {path}: dropped 1 of 13 strands with fewer than two distinct points"
    ]
    from hairjax._io._image import read_image

    image = read_image(out)
    assert np.isfinite(image).all() and image[..., 3].max() > 0  # the hair is seen
