"""Atomic output (hairjax/_files.py), shared by images, the CLI's JSON and the bench."""

import json
import os

import pytest

from hairjax._files import atomic_path, write_json


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
