"""Wall-clock time per step of a staged computation (the set-up's steps, the GL passes),
in seconds by name, for `render_profiled`'s and `render_gl`'s timings."""

from __future__ import annotations

import time
from collections.abc import Callable

__all__ = ["Laps"]


class Laps:
    """`lap(name)` ends a step: it adds the time since the previous call (or since the
    `Laps` was made) to `timings[name]`, so a step run in parts adds up. `wait` (optional)
    is called first, so that work queued elsewhere (GL's, by glFinish) counts in the step
    that queued it."""

    def __init__(self, wait: Callable[[], object] | None = None) -> None:
        self.timings: dict[str, float] = {}
        self._wait = wait
        self._clock = time.perf_counter()

    def __call__(self, name: str) -> None:
        if self._wait is not None:
            self._wait()
        now = time.perf_counter()
        self.timings[name] = self.timings.get(name, 0.0) + now - self._clock
        self._clock = now
