"""A command's outputs, checked before any work and written together.

Every path a command will write is declared up front as an `Output` (a file with the
extensions it may have, or a folder) and checked by `check_outputs` before anything is
loaded or rendered: the extension, that the target is not a directory (or, for a folder,
not a file), that the nearest existing ancestor is a directory a file can be created in
(tried, and removed). A
failure is a `BadOutput`, one line naming the path. `written_together` then writes a
command's files so that either all of them appear under their names or none does.
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path

__all__ = ["BadOutput", "Output", "check_outputs", "written_together", "IMAGE_SUFFIXES"]

IMAGE_SUFFIXES = (".exr", ".png")


class BadOutput(ValueError):
    """An output path the command cannot write; the message names the path."""


@dataclasses.dataclass(frozen=True)
class Output:
    """A path a command writes. `suffixes`: the extensions a file may have (lower case);
    empty for a folder the command fills. `option`: the option that named it, for messages."""

    path: Path
    suffixes: tuple[str, ...]
    option: str

    @property
    def is_folder(self) -> bool:
        return not self.suffixes


def _nearest_existing(path: Path) -> Path:
    """The path itself or its nearest ancestor that exists (`.` ends the walk)."""
    for candidate in (path, *path.parents):
        if candidate.exists():
            return candidate
    return Path(".")  # a relative path none of whose parts exist yet: the working directory


def check_output(out: Output) -> None:
    """Raise `BadOutput` if `out` cannot be written; leave nothing behind (the folder's
    writability is probed with a file that is removed at once)."""
    path = out.path
    where = f"{path} ({out.option})"
    if out.is_folder:
        if path.exists() and not path.is_dir():
            raise BadOutput(f"{where}: is a file; {out.option} takes a folder")
    else:
        if path.is_dir():
            raise BadOutput(
                f"{where}: is a directory; give a file name ending in {' or '.join(out.suffixes)}"
            )
        if path.suffix.lower() not in out.suffixes:
            found = f"'{path.suffix}'" if path.suffix else "no extension"
            raise BadOutput(f"{where}: unsupported extension {found}; use {' or '.join(out.suffixes)}")
    existing = _nearest_existing(path)
    if existing == path:
        existing = path if out.is_folder else path.parent
        if not existing.is_dir():  # a file path whose parent exists but is no folder
            raise BadOutput(f"{where}: {existing} is not a directory")
    elif not existing.is_dir():
        raise BadOutput(f"{where}: {existing} is a file, so the folder cannot be created")
    _probe(existing, where)


def _probe(folder: Path, where: str) -> None:
    """Create and remove an empty file in `folder`: the one test of writability that holds
    for root and for file systems whose permission bits say yes and whose writes fail
    (`os.access` passes /proc, a read-only mount's folder for some users, …)."""
    try:
        fd, probe = tempfile.mkstemp(prefix=".hairjax-probe-", dir=folder)
    except OSError as err:
        raise BadOutput(f"{where}: {folder} is not writable ({err.strerror or err})") from None
    os.close(fd)
    os.unlink(probe)


def check_outputs(outputs: Sequence[Output]) -> None:
    """Check every output (`check_output`) and that no two of them are the same path."""
    seen: dict[Path, str] = {}
    for out in outputs:
        check_output(out)
        key = out.path.resolve()
        if key in seen:
            raise BadOutput(f"{out.path}: named by both {seen[key]} and {out.option}")
        seen[key] = out.option


@contextlib.contextmanager
def written_together(paths: Sequence[Path]) -> Iterator[list[Path]]:
    """Yield a temporary path for each of `paths` (same folder, same extension). When the
    block succeeds they are all renamed into place; when it fails, all are removed and
    nothing appears. The writers inside write to the temporary paths."""
    from .._io._files import atomic_path

    with contextlib.ExitStack() as stack:
        temps = [Path(stack.enter_context(atomic_path(p, Path(p).suffix))) for p in paths]
        yield temps
        # Leaving the stack renames in reverse order; each rename is atomic. A rename can
        # only fail here if the folder changed under us after every file was written.
