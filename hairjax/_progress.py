"""Progress of long work: one concept for the whole package.

A library function that takes a while accepts `progress: Progress | None = None` and calls
`progress(done, total, message)` after each step: `done` of `total` steps are finished,
the last of them described by `message`. None (the default) is silent: the library prints
nothing unless asked. A call may repeat `done` with a new message (work outside the count,
such as the sweep's reference render, or a note such as "resuming").

`reporter(title)` makes the `Progress` a command line hands in:

- on a terminal (the stream's `isatty()`): a live `rich` bar, `title: message`, done/total,
  elapsed time;
- otherwise (a log, a pipe, CI): one plain line per call, flushed at once,
  `compare: 3/8 gl render (4.2 s)`, the seconds being the time since the previous call
  (that step's);
- with `quiet`: nothing.

`rich` is imported only when a bar is drawn: `import hairjax` stays light.
"""

from __future__ import annotations

import contextlib
import sys
import time
from collections.abc import Callable, Iterator
from typing import IO, Protocol, cast, runtime_checkable

__all__ = ["Progress", "Stream", "reporter", "progress_of", "counter"]


@runtime_checkable
class Progress(Protocol):
    """What library functions accept as `progress=`: called after each step."""

    def __call__(self, done: int, total: int, message: str = "") -> None: ...


@runtime_checkable
class Stream(Protocol):
    """Where reports go: a text stream (`sys.stderr`, `io.StringIO`); one whose `isatty()`
    is true gets the live bar."""

    def write(self, text: str, /) -> int: ...

    def flush(self) -> None: ...


def _silent(done: int, total: int, message: str = "") -> None:
    return None


class _Lines:
    """One plain line per step: `title: done/total message (step seconds)`."""

    def __init__(self, title: str, stream: Stream):
        self.title, self.stream, self.last = title, stream, time.perf_counter()

    def __call__(self, done: int, total: int, message: str = "") -> None:
        now = time.perf_counter()
        text = f"{self.title}: {done}/{total}"
        if message:
            text += f" {message}"
        print(f"{text} ({now - self.last:.1f} s)", file=self.stream, flush=True)
        self.last = now


@contextlib.contextmanager
def _bar(title: str, stream: Stream) -> Iterator[Progress]:
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, TextColumn, TimeElapsedColumn
    from rich.progress import Progress as RichProgress

    bar = RichProgress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=Console(file=cast(IO[str], stream)),
    )
    task = bar.add_task(title, total=None)

    def advance(done: int, total: int, message: str = "") -> None:
        description = f"{title}: {message}" if message else title
        bar.update(task, completed=done, total=total, description=description)

    with bar:
        yield advance


def _is_terminal(stream: Stream) -> bool:
    isatty = getattr(stream, "isatty", None)
    return bool(isatty and isatty())


@contextlib.contextmanager
def reporter(title: str, *, quiet: bool = False, stream: Stream | None = None) -> Iterator[Progress]:
    """A `Progress` for the length of the `with` block, writing to `stream` (default
    standard error): a live bar on a terminal, one line per step elsewhere, nothing when
    `quiet`. The bar is taken down when the block ends, also on an error."""
    if quiet:
        yield _silent
        return
    stream = sys.stderr if stream is None else stream
    if _is_terminal(stream):
        with _bar(title, stream) as advance:
            yield advance
    else:
        yield _Lines(title, stream)


@contextlib.contextmanager
def progress_of(progress: Progress | bool | None, title: str) -> Iterator[Progress]:
    """The `Progress` a library function calls, from what its caller passed: a callable
    as it is, None or False silent, True a `reporter(title)` on standard error.

    True and False are the older `progress=` flags (the CLI passed `sys.stderr.isatty()`);
    they are accepted for one release, after which only a `Progress` or None is."""
    if progress is True:
        with reporter(title) as advance:
            yield advance
    elif progress is None or progress is False:
        yield _silent
    else:
        yield progress


def counter(total: int, progress: Progress | None) -> Callable[[str], None]:
    """`step(message)`: counts one more finished step of `total` and reports it to
    `progress` (silent for None)."""
    done = 0

    def step(message: str) -> None:
        nonlocal done
        done += 1
        if progress is not None:
            progress(done, total, message)

    return step
