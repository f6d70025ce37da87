"""USC-HairSalon hair (``.data``), the 343 hairstyles of Hu et al., "Single-View Hair
Modeling Using A Hairstyle Database" (SIGGRAPH 2015); little-endian.

Layout::

    i32  strand count S
    then S times:
        i32          vertex count n of the strand
        n x 3 x f32  its vertices, x y z

There is no header, magic number or padding: the file ends after the last strand. Read as
the data set's users read it: `load_hair` and `_save_hair_data` in c-he/perm's
``src/hair/io.py`` (``struct.unpack('i', ...)``, then ``'f' * num_points * 3``; the writer
the same ``struct.pack`` calls in that order), and ``io::load_data`` / ``io::save_data``
in kenshi84/hairutil's ``src/io/data.cpp`` (one ``int`` count, per strand an ``int`` vertex
count and that many float x, y, z). Both use the machine's byte order with 4-byte ints
and floats; the data set was written on little-endian machines, so that is what is read
and written here. The data set has strands of one vertex (scalp positions without hair);
`load_hair` drops them (docs/scenes.md "Input ranges").
"""

from __future__ import annotations

import struct

import numpy as np

from .._errors import HairFormatError

__all__ = ["parse_data", "data_bytes"]

_COUNT = struct.Struct("<i")


def parse_data(data: bytes, path) -> dict:
    """Parse the bytes of a USC-HairSalon ``.data`` file.

    Returns a dict with `points` (float64 [P, 3]), `offsets` (int64 [S + 1]), `color`
    (None: the format stores none) and `attributes` (empty). Raises `HairFormatError`
    naming the problem (and the strand) for any malformed input.
    """

    def fail(problem: str):
        raise HairFormatError(path, problem)

    size = len(data)
    if size < 4:
        fail(f"file is {size} bytes, shorter than the 4-byte strand count")
    (n_strands,) = _COUNT.unpack_from(data, 0)
    if n_strands <= 0:
        fail(f"the strand count is {n_strands}; it must be ≥ 1")
    # Each strand takes at least its 4-byte count: an absurd count fails before any loop.
    if 4 + 4 * n_strands > size:
        fail(f"truncated: {n_strands} strands need at least {4 + 4 * n_strands} bytes, the file has {size}")
    counts = np.empty(n_strands, dtype=np.int64)
    count_at = np.empty(n_strands + 1, dtype=np.int64)  # where each i32 count starts
    count_at[0] = 0
    at = 4
    for s in range(n_strands):
        if at + 4 > size:
            fail(f"truncated in strand {s}: its vertex count is missing (the file ends at byte {size})")
        (n,) = _COUNT.unpack_from(data, at)
        if n <= 0:
            fail(f"strand {s} has vertex count {n}; it must be ≥ 1")
        end = at + 4 + 12 * n
        if end > size:
            fail(f"truncated in strand {s}: its {n} vertices need bytes up to {end}, the file has {size}")
        counts[s], count_at[s + 1] = n, at
        at = end
    if at != size:
        fail(f"{size - at} unexpected bytes after the last strand (counts do not match the data)")
    # Every byte that is not part of a count is a vertex coordinate, in order.
    is_vertex = np.ones(size, dtype=bool)
    is_vertex[(count_at[:, None] + np.arange(4)).ravel()] = False
    points = np.frombuffer(data, np.uint8)[is_vertex].view("<f4").reshape(-1, 3)
    offsets = np.concatenate([[0], np.cumsum(counts)])
    return {"points": points.astype(np.float64), "offsets": offsets, "color": None, "attributes": {}}


def data_bytes(points: np.ndarray, offsets: np.ndarray) -> bytes:
    """The ``.data`` bytes of strands (points float64 [P, 3] as float32, offsets [S + 1]),
    in the layout above."""
    counts = np.diff(offsets)
    parts = [_COUNT.pack(len(counts))]
    flat = np.asarray(points, dtype="<f4")
    for s, n in enumerate(counts):
        parts.append(_COUNT.pack(int(n)))
        parts.append(flat[offsets[s] : offsets[s + 1]].tobytes())
    return b"".join(parts)
