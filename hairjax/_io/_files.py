"""Atomic file output: a result appears complete under its name, or not at all."""

from __future__ import annotations

import contextlib
import csv
import io
import json
import os
import tempfile
from pathlib import Path

__all__ = ["atomic_path", "write_json", "write_text", "write_csv"]


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


def write_text(path, text: str) -> Path:
    """Write `text` to `path`, atomically."""
    with atomic_path(path, Path(path).suffix) as tmp:
        with open(tmp, "w") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
    return Path(path)


def write_json(path, data, **dump_options) -> Path:
    """Write `data` as indented JSON, atomically."""
    return write_text(path, json.dumps(data, indent=2, **dump_options) + "\n")


def write_csv(path, columns, rows, float_format: str | None = None) -> Path:
    """Write dict `rows` as CSV with a header of `columns` (other keys are ignored), atomically.
    None is written as an empty cell; floats with `float_format` when given (e.g. ".6g")."""

    def cell(v):
        if v is None:
            return ""
        return format(v, float_format) if float_format and isinstance(v, float) else v

    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=list(columns), extrasaction="ignore", lineterminator="\n")
    writer.writeheader()
    for r in rows:
        writer.writerow({k: cell(r.get(k)) for k in columns})
    return write_text(path, buf.getvalue())
