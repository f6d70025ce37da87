"""Atomic output (hairjax/_io/_files.py), shared by images, the CLI's JSON and the bench."""

import json
import os

import pytest

from hairjax._io._files import atomic_path, write_csv, write_json, write_text


def test_failed_block_leaves_nothing(tmp_path):
    target = tmp_path / "out" / "r.json"
    with pytest.raises(RuntimeError):
        with atomic_path(target, ".json") as tmp:
            with open(tmp, "w") as f:
                f.write("{half")
            raise RuntimeError("interrupted")
    assert not target.exists() and os.listdir(target.parent) == []


def test_existing_file_survives_a_failed_rewrite(tmp_path):
    target = tmp_path / "r.json"
    write_json(target, {"a": 1})
    with pytest.raises(ValueError):
        write_json(target, {"a": float("nan")}, allow_nan=False)
    assert json.loads(target.read_text()) == {"a": 1}
    assert os.listdir(tmp_path) == ["r.json"]


def test_plain_write_permissions(tmp_path):
    path = write_json(tmp_path / "r.json", [1, 2])
    umask = os.umask(0)
    os.umask(umask)
    assert path.stat().st_mode & 0o777 == 0o666 & ~umask


def test_write_csv_formats_and_ignores(tmp_path):
    rows = [{"a": 1, "b": 0.123456789, "c": None, "extra": "dropped"}, {"a": "x", "b": 2.0, "c": "y"}]
    path = write_csv(tmp_path / "t.csv", ("a", "b", "c"), rows, float_format=".3g")
    assert path.read_text() == "a,b,c\n1,0.123,\nx,2,y\n"
    assert write_csv(tmp_path / "u.csv", ("b",), rows).read_text() == "b\n0.123456789\n2.0\n"


def test_write_text_replaces_atomically(tmp_path):
    target = write_text(tmp_path / "t.md", "first\n")
    assert write_text(target, "second\n").read_text() == "second\n"
    assert [p.name for p in tmp_path.iterdir()] == ["t.md"]  # no temporary left behind
