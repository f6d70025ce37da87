"""What GL renders ask of the GPU, counted: draw calls, compute dispatches, memory barriers,
framebuffer binds (a pass binds its target), bytes uploaded and read back, and waits
(glFinish).

For `hairjax bench` (BENCHMARKS.md): times on llvmpipe are mostly the CPU's, while the
counts show a change in the work itself on any driver. `counted_gl_work()` wraps
moderngl's methods for the duration of its `with` block only, and puts them back after."""

from __future__ import annotations

import contextlib
import dataclasses
from collections.abc import Iterator

__all__ = ["GLWork", "counted_gl_work"]


@dataclasses.dataclass
class GLWork:
    """The counts of one `counted_gl_work` block."""

    draws: int = 0
    dispatches: int = 0
    barriers: int = 0
    binds: int = 0
    uploaded: int = 0  # bytes
    read_back: int = 0  # bytes
    waits: int = 0


def _nbytes(data) -> int:
    return 0 if data is None else memoryview(data).nbytes


@contextlib.contextmanager
def counted_gl_work() -> Iterator[GLWork]:
    """Count the GL work of the block (module docstring)."""
    import moderngl

    work = GLWork()

    def count(cls, name, add):
        original = getattr(cls, name)

        def wrapper(self, *args, **kwargs):
            result = original(self, *args, **kwargs)
            add(args, kwargs, result)
            return result

        return cls, name, original, wrapper

    def data_of(args, kwargs):
        return kwargs.get("data", args[0] if args else None)

    def texture_data(args, kwargs):  # Context.texture(size, components, data=None, ...)
        return kwargs.get("data", args[2] if len(args) > 2 else None)

    def add(field, amount):
        setattr(work, field, getattr(work, field) + amount)

    wrapped = [
        count(moderngl.VertexArray, "render", lambda a, k, r: add("draws", 1)),
        count(moderngl.VertexArray, "transform", lambda a, k, r: add("draws", 1)),
        count(moderngl.ComputeShader, "run", lambda a, k, r: add("dispatches", 1)),
        count(moderngl.Context, "memory_barrier", lambda a, k, r: add("barriers", 1)),
        count(moderngl.Framebuffer, "use", lambda a, k, r: add("binds", 1)),
        count(moderngl.Context, "finish", lambda a, k, r: add("waits", 1)),
        count(moderngl.Context, "buffer", lambda a, k, r: add("uploaded", _nbytes(data_of(a, k)))),
        count(moderngl.Buffer, "write", lambda a, k, r: add("uploaded", _nbytes(data_of(a, k)))),
        count(moderngl.Texture, "write", lambda a, k, r: add("uploaded", _nbytes(data_of(a, k)))),
        count(moderngl.Context, "texture", lambda a, k, r: add("uploaded", _nbytes(texture_data(a, k)))),
        count(moderngl.Buffer, "read", lambda a, k, r: add("read_back", _nbytes(r))),
        count(moderngl.Framebuffer, "read", lambda a, k, r: add("read_back", _nbytes(r))),
        count(moderngl.Texture, "read", lambda a, k, r: add("read_back", _nbytes(r))),
    ]
    try:
        for cls, name, _, wrapper in wrapped:
            setattr(cls, name, wrapper)
        yield work
    finally:
        for cls, name, original, _ in wrapped:
            setattr(cls, name, original)
