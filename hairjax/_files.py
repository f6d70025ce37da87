"""Atomic file output: a result appears complete under its name, or not at all."""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from pathlib import Path

__all__ = ["atomic_path", "write_json"]


@contextlib.contextmanager
def atomic_path(path, suffix: str = ""):
    """Yield a temporary path in `path`'s folder; when the block succeeds it is renamed
    over `path` (with a plain write's permissions), when it fails it is removed."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=suffix, dir=path.parent)
    os.close(fd)
    try:
        yield tmp
        # mkstemp creates the file private (0600); give it the permissions of a plain write.
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def write_json(path, data, **dump_options) -> Path:
    """Write `data` as indented JSON, atomically."""
    with atomic_path(path, ".json") as tmp:
        with open(tmp, "w") as f:
            json.dump(data, f, indent=2, **dump_options)
            f.write("\n")
            f.flush()
            os.fsync(f.fileno())
    return Path(path)
