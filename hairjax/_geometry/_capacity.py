"""The set-up's capacity policy (docs/model.md §5): the bytes it holds per fragment, and
the refusal, before anything is allocated, of a scene whose fragments exceed the memory
available (`SceneTooLarge`)."""

from __future__ import annotations

import numpy as np

from .._errors import SceneTooLarge
from ._host import available_memory

__all__ = ["fragment_bytes", "check_memory", "fragment_bucket", "MIN_BUCKET"]

MIN_BUCKET = 1 << 12  # the smallest bucket: a few tens of kB per field


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
    raster, n_segments: int, capacity: int, dtype: np.dtype, depth: bool, width: int, height: int
) -> None:
    """The capacity policy (docs/model.md §5): the fields are sized for every candidate,
    but only what is written becomes resident. When even the candidates' bound needs
    more than the memory available, the covered candidates are counted first (a pass
    that writes nothing), and a scene whose fragments need more is refused before
    anything is allocated (`SceneTooLarge`).

    `raster`: the raster loop with all but its segment range, count flag and outputs
    bound (`_raster`); `capacity`: the candidates' bound on the fragments."""
    per_fragment = fragment_bytes(dtype.itemsize, depth)
    available = available_memory()
    if available is None or capacity * per_fragment <= available:
        return
    ints, floats = np.empty(0, np.int32), np.empty(0, dtype)  # not written when counting
    count = raster(0, n_segments, True, ints, ints, floats, floats, floats)
    if count * per_fragment > available:
        raise SceneTooLarge(
            f"the {width}x{height} raster of this scene holds {count:,} fragments, which need "
            f"{count * per_fragment / 2**30:.1f} GiB ({per_fragment} bytes each) in the geometry "
            f"set-up alone; {available / 2**30:.1f} GiB of memory is available: render fewer "
            "pixels (--size), fewer or thinner strands, or on a machine with more memory"
        )
