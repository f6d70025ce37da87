"""A command's outputs, checked before any work and written together.

Every path a command will write is declared up front as an `Output` (a file with the
extensions it may have, or a folder) and checked by `check_outputs` before anything is
loaded or rendered: the extension, that the target is not a directory (or, for a folder,
not a file), that the nearest existing ancestor is a directory a file can be created in
(tried, and removed). A failure is a `BadOutput`, one line naming the path. Once the
outputs' sizes are known (the scene read), `check_free_space` compares them with the free
space (statvfs), before the work. `written_together` then writes a command's files so that
either all of them appear under their names or none does, the images last.
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path

__all__ = [
    "BadOutput",
    "Output",
    "check_outputs",
    "check_free_space",
    "image_bytes",
    "written_together",
    "IMAGE_SUFFIXES",
    "FILE_OVERHEAD",
]

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


def free_bytes(folder: Path) -> int:
    """Bytes an unprivileged user may still write on `folder`'s file system (statvfs)."""
    stat = os.statvfs(folder)
    return stat.f_bavail * stat.f_frsize


def image_bytes(path: Path, width: int, height: int) -> int:
    """An upper bound on the size of the image file `write_image` writes: EXR as float32
    RGBA (4 × 4 bytes a pixel, uncompressed), PNG as 8-bit RGB (3 bytes a pixel and a
    filter byte a row, when deflate gains nothing), each with `FILE_OVERHEAD` for headers."""
    per_pixel = 16 if path.suffix.lower() == ".exr" else 3
    return width * height * per_pixel + height + FILE_OVERHEAD


# Headers and metadata of an image, or a small text file (a sidecar, a fit's JSON): bytes.
FILE_OVERHEAD = 64 * 1024


def check_free_space(sizes: Sequence[tuple[Output, int]]) -> None:
    """Raise `BadOutput` unless each file system has room for the outputs written on it
    (`sizes`: an output and its expected bytes): the check comes before the work, so a
    full disk is found before a long render, not in its last step. The files already
    there are replaced only once the new ones are complete, so their space does not count."""
    need: dict[int, tuple[int, Path, list[Output]]] = {}
    for out, size in sizes:
        folder = _nearest_existing(out.path if out.is_folder else out.path.parent)
        device = os.stat(folder).st_dev
        total, _, outs = need.get(device, (0, folder, []))
        need[device] = (total + size, folder, [*outs, out])
    for total, folder, outs in need.values():
        free = free_bytes(folder)
        if free < total:
            names = ", ".join(f"{o.path} ({o.option})" for o in outs)
            raise BadOutput(f"{names}: needs about {_size(total)} but {folder} has {_size(free)} free")


def _size(count: int) -> str:
    if count < 1024:
        return f"{count} bytes"
    exponent = min(3, (count.bit_length() - 1) // 10)
    return f"{count / 1024**exponent:.1f} {('KiB', 'MiB', 'GiB')[exponent - 1]}"


@contextlib.contextmanager
def written_together(paths: Sequence[Path]) -> Iterator[list[Path]]:
    """Yield a temporary path for each of `paths` (same folder, same extension). When the
    block succeeds they are renamed into place, images last (`IMAGE_SUFFIXES`), so an
    image appears only beside its complete companions, and all of them or none
    (`replace_together`); when it fails, all are removed and nothing appears. The writers
    inside write to the temporary paths; an `OSError` from them (a full disk, a failed
    write) is re-raised naming the user's path, not the temporary one."""
    from .._io._files import replace_together, temporary_beside

    paths = [Path(p) for p in paths]
    temps: list[Path] = []
    try:
        for p in paths:
            temps.append(temporary_beside(p, p.suffix))
        try:
            yield list(temps)
        except OSError as err:
            raise _naming_user_path(err, temps, paths) from None
        order = sorted(range(len(paths)), key=lambda i: paths[i].suffix.lower() in IMAGE_SUFFIXES)
        replace_together([(temps[i], paths[i]) for i in order])
    finally:
        for tmp in temps:
            tmp.unlink(missing_ok=True)


def _naming_user_path(err: OSError, temps: Sequence[Path], paths: Sequence[Path]) -> OSError:
    """`err` with each temporary path in its file name and message replaced by the user's."""
    text, filename = str(err), err.filename
    for tmp, path in zip(temps, paths):
        text = text.replace(str(tmp), str(path))
        if filename is not None and str(tmp) in str(filename):
            filename = str(path)
    if err.errno is not None and err.strerror and filename is not None:
        return OSError(err.errno, err.strerror, str(filename))
    return OSError(text)
