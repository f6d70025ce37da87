"""Atomic file output: a result appears complete under its name, or not at all."""

from __future__ import annotations

import contextlib
import csv
import io
import json
import os
import tempfile
from collections.abc import Sequence
from pathlib import Path

__all__ = ["atomic_path", "temporary_beside", "replace_together", "write_json", "write_text", "write_csv"]


def temporary_beside(path: Path, suffix: str = "") -> Path:
    """An empty temporary file in `path`'s folder (created with its parents), named after
    it: `.NAME.XXXXXX` + `suffix`. A rename over `path` is then atomic (one file system)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=suffix, dir=path.parent)
    os.close(fd)
    return Path(tmp)


def _plain_permissions(tmp: Path) -> None:
    # mkstemp creates the file private (0600); give it the permissions of a plain write.
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)


@contextlib.contextmanager
def atomic_path(path, suffix: str = ""):
    """Yield a temporary path in `path`'s folder; when the block succeeds it is renamed
    over `path` (with a plain write's permissions), when it fails it is removed."""
    path = Path(path)
    tmp = temporary_beside(path, suffix)
    try:
        yield str(tmp)
        _plain_permissions(tmp)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def replace_together(pairs: Sequence[tuple[Path, Path]]) -> None:
    """Rename each written temporary over its path, in the order given, so that all the
    paths hold the new files or, if a rename fails, all hold what they held before.

    Each file a rename would replace is first moved aside (same folder); when a later
    rename fails, the renames done are undone and the files moved aside come back. The
    temporaries are removed either way. **Raises:** `OSError` naming the path (never a
    temporary) whose rename failed.
    """
    done: list[tuple[Path, Path | None]] = []  # (path, what it held before, moved aside)
    try:
        for tmp, path in pairs:
            _plain_permissions(tmp)
            old = None
            if os.path.lexists(path) and not path.is_dir():
                old = temporary_beside(path, ".old")
                os.replace(path, old)
            done.append((path, old))
            try:
                os.replace(tmp, path)
            except OSError as err:
                raise OSError(err.errno, err.strerror or str(err), str(path)) from None
    except BaseException:
        for path, old in reversed(done):
            if old is not None:
                os.replace(old, path)
            elif os.path.lexists(path) and not path.is_dir():
                path.unlink()  # a path that did not exist before this command
        raise
    finally:
        for tmp, _ in pairs:
            tmp.unlink(missing_ok=True)
    for _, old in done:
        if old is not None:
            old.unlink(missing_ok=True)


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
