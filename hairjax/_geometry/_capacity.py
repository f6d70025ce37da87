"""The set-up's capacity policy (docs/model.md §5): the bytes it holds per fragment, and
the refusal, before anything is allocated, of a scene whose fragments exceed the memory
available (`SceneTooLarge`)."""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import ParamSpec, TypeVar

import numpy as np

from .._errors import SceneTooLarge
from ._host import available_memory, in_parallel

__all__ = [
    "fragment_bytes",
    "check_memory",
    "fragment_bucket",
    "memory_size",
    "check_generated",
    "refuses_out_of_memory",
    "MIN_BUCKET",
]

MIN_BUCKET = 1 << 12  # the smallest bucket: a few tens of kB per field


def memory_size(n: int | float) -> str:
    """Bytes for a message: GiB, MiB or kB with one decimal, or bytes."""
    for unit, size in (("GiB", 2**30), ("MiB", 2**20), ("kB", 2**10)):
        if n >= size:
            return f"{n / size:.1f} {unit}"
    return f"{int(n)} bytes"


# What procedural hair holds while it is generated (`_scene/_procedural`): per point its
# position (float64 xyz) and the generators' per-point temporaries, per strand its root,
# direction, length, offsets and the joint loop's temporaries.
GENERATED_POINT_BYTES = 96
GENERATED_STRAND_BYTES = 256


def check_generated(strands: int, points: int) -> None:
    """Refuse (`SceneTooLarge`), before anything is generated, procedural hair of
    `strands` strands of `points` points that needs more memory than is available."""
    need = strands * (points * GENERATED_POINT_BYTES + GENERATED_STRAND_BYTES)
    available = available_memory()
    if available is not None and need > available:
        raise SceneTooLarge(
            f"hair.strands = {strands:,} strands of hair.points = {points:,} points: generating "
            f"them needs {memory_size(need)}; {memory_size(available)} of memory is available"
        )


P = ParamSpec("P")
T = TypeVar("T")

# What NumPy and XLA say when an allocation fails: a MemoryError, NumPy's ValueError for
# a size beyond its index type, XLA's RESOURCE_EXHAUSTED.
_OUT_OF_MEMORY = ("array is too big", "Maximum allowed size exceeded", "RESOURCE_EXHAUSTED")


def refuses_out_of_memory(fn: Callable[P, T]) -> Callable[P, T]:
    """`fn(scene, ...)` with an allocation that fails despite the capacity estimate
    (docs/model.md §5) refused as `SceneTooLarge`, in one line that names the scene's
    sizes instead of NumPy's or XLA's words."""

    @functools.wraps(fn)
    def refusing(*args: P.args, **kwargs: P.kwargs) -> T:
        try:
            return fn(*args, **kwargs)
        except SceneTooLarge:
            raise
        except (MemoryError, ValueError, RuntimeError) as e:
            if not isinstance(e, MemoryError) and not any(words in str(e) for words in _OUT_OF_MEMORY):
                raise
            raise SceneTooLarge(_ran_out(args[0] if args else kwargs.get("scene"))) from e

    return refusing


def _ran_out(scene) -> str:
    """The scene's sizes, for an allocation that failed beyond the estimate."""
    try:
        cam, strands = scene.camera, scene.strands
        sizes = f"camera {cam.width}x{cam.height} (--size), hair.strands = {strands.num_strands:,}"
        maps = scene.shadows.planned_maps()[1] if scene.shadows.casts else ""
    except AttributeError:  # fires for an argument that is not a Scene: no sizes to name
        sizes, maps = "", ""
    named = ", ".join(part for part in (sizes, maps) if part)
    available = available_memory()
    return (
        "this render ran out of memory beyond its capacity estimate (docs/model.md §5)"
        + (f" at {named}" if named else "")
        + ("" if available is None else f"; {memory_size(available)} of memory is available")
        + ": render fewer pixels (--size), fewer or thinner strands, or fewer shadow maps"
    )


def fragment_bucket(n: int) -> int:
    """`n` rounded up to a bucket: eight steps per octave (2^k, 2^k·9/8, …, 2^k·15/8), at
    least MIN_BUCKET. The geometry stage's fragment arrays are padded to it, so the programs
    that read them compile once per bucket, not once per fragment count (a camera moved
    by a degree, an animation's next frame), at most 12.5 % more entries."""
    n = max(int(n), MIN_BUCKET)
    step = 1 << max(n.bit_length() - 4, 0)  # 2^k / 8 for 2^k ≤ n < 2^(k+1)
    return -(-n // step) * step


def fragment_bytes(float_size: int, depth: bool) -> int:
    """Bytes the set-up holds at once per fragment: the raster's fields (pixel, segment,
    coverage, t and depth if asked) and as many again grouped by pixel or planned for Ω."""
    raster = 8 + (3 if depth else 2) * float_size
    return raster + 8 + 2 * float_size


def check_memory(
    raster, bounds: list[int], seg_start: np.ndarray, dtype: np.dtype, depth: bool, width: int, height: int
) -> list[int]:
    """The capacity policy of one raster (docs/model.md §5): where each piece's share of
    the fields begins, and (the last entry) the fields' length.

    The fields are sized for every candidate, and only what is written becomes resident.
    When even the candidates' bound needs more than the memory available, the covered
    candidates are counted first, piece by piece on every core (a pass that writes
    nothing): the fields are then sized for exactly those (an allocation of the
    candidates' bound could fail on its own, beyond the system's overcommit), and a raster
    whose fragments need more is refused before anything is allocated (`SceneTooLarge`).

    `raster`: the raster loop with all but its segment range, count flag and outputs
    bound (`_raster`); `bounds`: the pieces' segment ranges; `seg_start`: each segment's
    first candidate, the last entry their number."""
    capacity = int(seg_start[-1])
    per_fragment = fragment_bytes(dtype.itemsize, depth)
    available = available_memory()
    if available is None or capacity * per_fragment <= available:
        return [int(seg_start[a]) for a in bounds]
    ints, floats = np.empty(0, np.int32), np.empty(0, dtype)  # not written when counting
    counts = in_parallel(
        [
            functools.partial(raster, a, b, True, ints, ints, floats, floats, floats)
            for a, b in zip(bounds[:-1], bounds[1:])
        ]
    )
    count = sum(counts)
    if count * per_fragment > available:
        raise SceneTooLarge(
            f"the {width}x{height} raster of this scene holds {count:,} fragments, which need "
            f"{count * per_fragment / 2**30:.1f} GiB ({per_fragment} bytes each) in the geometry "
            f"set-up alone; {available / 2**30:.1f} GiB of memory is available: render fewer "
            "pixels (--size), fewer or thinner strands, or on a machine with more memory"
        )
    return [0, *np.cumsum(counts).tolist()]
