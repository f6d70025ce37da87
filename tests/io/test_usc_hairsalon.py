"""USC-HairSalon ``.data`` (hairjax/_io/_usc.py) against the data set's users' own code.

`reference_write` and `reference_read` reproduce, call for call, `_save_hair_data` and
`load_hair` of c-he/perm's ``src/hair/io.py`` (Perm, He et al. 2025, which loads the
USC-HairSalon strands): ``struct.pack('i', num_strands)``, then per strand
``struct.pack('i', num_points)`` and ``struct.pack('f' * num_points * 3, ...)``.
perm's reader reshapes to one vertex count for all strands; `reference_read_ragged`
keeps its loop but not the reshape, as kenshi84/hairutil's ``io::load_data``
(``src/io/data.cpp``) reads strands of any count. Native byte order is little-endian on
every machine these tests run on (asserted below), as on the machines the data set came from.
"""

from __future__ import annotations

import struct
import sys
import warnings

import numpy as np
import pytest

import hairjax as hj
from hairjax._errors import HairFormatError
from hairjax._io import load_hair, save_hair
from hairjax._values._strands import Strands

assert sys.byteorder == "little"  # struct's native 'i' and 'f' are then the file's '<i', '<f'


def reference_write(path, data: np.ndarray) -> None:
    """c-he/perm's `_save_hair_data` (strands of one vertex count, [S, N, 3])."""
    num_strands, num_points = data.shape[:2]
    with open(path, "wb") as f:
        f.write(struct.pack("i", num_strands))
        for i in range(num_strands):
            f.write(struct.pack("i", num_points))
            f.write(struct.pack("f" * num_points * 3, *data[i].flatten().tolist()))


def reference_read(path) -> np.ndarray:
    """c-he/perm's `load_hair`: [S, N, 3]."""
    with open(path, "rb") as f:
        data = f.read()
    num_strands = struct.unpack("i", data[:4])[0]
    strands = []
    idx = 4
    for _ in range(num_strands):
        num_points = struct.unpack("i", data[idx : idx + 4])[0]
        points = struct.unpack("f" * num_points * 3, data[idx + 4 : idx + 4 + 4 * num_points * 3])
        strands.append(list(points))
        idx = idx + 4 + 4 * num_points * 3
    return np.array(strands).reshape((num_strands, -1, 3))


def reference_read_ragged(path) -> list[np.ndarray]:
    """perm's loop without its reshape: strands of any vertex count (as hairutil reads)."""
    with open(path, "rb") as f:
        data = f.read()
    (num_strands,) = struct.unpack("i", data[:4])
    strands, idx = [], 4
    for _ in range(num_strands):
        (num_points,) = struct.unpack("i", data[idx : idx + 4])
        points = struct.unpack("f" * num_points * 3, data[idx + 4 : idx + 4 + 12 * num_points])
        strands.append(np.array(points).reshape(num_points, 3))
        idx += 4 + 12 * num_points
    assert idx == len(data)
    return strands


def ragged_write(path, strands) -> None:
    """perm's writer, one strand at a time, with each strand's own vertex count."""
    with open(path, "wb") as f:
        f.write(struct.pack("i", len(strands)))
        for s in strands:
            f.write(struct.pack("i", len(s)))
            f.write(struct.pack("f" * len(s) * 3, *np.asarray(s).flatten().tolist()))


RNG = np.random.default_rng(7)
GRID = np.cumsum(RNG.normal(scale=0.01, size=(6, 100, 3)), axis=1).astype(np.float32)  # 100 vertices each


def test_reads_what_the_reference_writes(tmp_path):
    path = tmp_path / "strands00001.data"
    reference_write(path, GRID)
    strands = load_hair(path)
    assert strands.num_strands == 6 and strands.offsets.tolist() == list(range(0, 601, 100))
    assert np.array_equal(strands.points, GRID.reshape(-1, 3).astype(np.float64))
    assert strands.color is None and strands.attributes == {}


def test_reference_reads_what_hairjax_writes(tmp_path):
    path = hj.save_hair(Strands(GRID.reshape(-1, 3), np.arange(7) * 100, 1.0, 1.0), tmp_path / "out.data")
    assert np.array_equal(reference_read(path), GRID)
    assert path.stat().st_size == 4 + 6 * (4 + 100 * 12)


def test_ragged_round_trip_and_one_point_strands(tmp_path):
    """The data set stores empty scalp positions as one-vertex strands: dropped, counted."""
    strands = [GRID[0, :3], GRID[1, :1], GRID[2, :7], GRID[3, :2]]
    path = tmp_path / "ragged.data"
    ragged_write(path, strands)
    with pytest.warns(UserWarning, match=r"ragged\.data: dropped 1 of 4 strands"):
        loaded = load_hair(path)
    assert loaded.offsets.tolist() == [0, 3, 10, 12]
    assert np.array_equal(loaded.points, np.concatenate([strands[0], strands[2], strands[3]]))
    again = save_hair(loaded, tmp_path / "again.DATA")  # suffix in any case
    back = reference_read_ragged(again)
    assert [len(s) for s in back] == [3, 7, 2]
    assert np.array_equal(np.concatenate(back), loaded.points)
    reloaded = load_hair(again)
    assert np.array_equal(reloaded.points, loaded.points) and np.array_equal(reloaded.offsets, loaded.offsets)


def _bytes(*counts_and_points) -> bytes:
    out = b""
    for item in counts_and_points:
        out += struct.pack("<i", item) if isinstance(item, int) else np.asarray(item, "<f4").tobytes()
    return out


TWO = np.arange(6, dtype=np.float32)  # one strand's two vertices


@pytest.mark.parametrize(
    "data, message",
    [
        (b"\x01\x00", "shorter than the 4-byte strand count"),
        (_bytes(0), "the strand count is 0"),
        (_bytes(-3), "the strand count is -3"),
        (_bytes(2_000_000_000, 2, TWO), "2000000000 strands need at least"),
        (_bytes(2, 2, TWO), "truncated in strand 1: its vertex count is missing"),
        (_bytes(1, 3, TWO), "truncated in strand 0: its 3 vertices need bytes up to 44"),
        (_bytes(2, 2, TWO, 0), "strand 1 has vertex count 0"),
        (_bytes(1, 2, TWO, 5), "4 unexpected bytes after the last strand"),
        (_bytes(1, 2, [0, 0, 0, 1, np.nan, 0]), "point 1 has a NaN or infinite coordinate"),
        (_bytes(1, 2, [0, 0, 0, 1, 3e38, 0]), r"point 1 = \(1, 3e\+38, 0\) lies beyond ±1e\+18"),
    ],
)
def test_malformed(tmp_path, data, message):
    path = tmp_path / "bad.data"
    path.write_bytes(data)
    with pytest.raises(HairFormatError, match=rf"^{path}: .*{message}"):
        load_hair(path)


def test_save_hair_names_the_formats_it_writes(tmp_path):
    strands = Strands(GRID.reshape(-1, 3), np.arange(7) * 100, 1.0, 1.0)
    writes = r"\(writes: \.data, \.usd, \.usda, \.usdc, \.usdz\)"
    with pytest.raises(
        HairFormatError,
        match=rf"out\.hair: hairjax reads Cem Yuksel HAIR files but does not write them {writes}$",
    ):
        save_hair(strands, tmp_path / "out.hair")
    with pytest.raises(
        HairFormatError, match=r"out\.xyz: unknown file type '\.xyz' \(known: \.hair, .*\.usdz\)$"
    ):
        save_hair(strands, tmp_path / "out.xyz")
    assert list(tmp_path.iterdir()) == []


def test_corrupted_files_give_one_error_or_finite_strands(tmp_path):
    """Seeded byte flips in a good file: a HairFormatError naming it, or finite strands
    (possibly with the dropped-strand warning); never another exception or a numpy warning."""
    good = tmp_path / "good.data"
    reference_write(good, GRID[:3, :5])
    data = good.read_bytes()
    rng = np.random.default_rng(31)
    path = tmp_path / "corrupt.data"
    for _ in range(200):
        corrupted = bytearray(data)
        for at in rng.integers(0, len(data), size=rng.integers(1, 4)):
            corrupted[at] = int(rng.integers(0, 256))
        path.write_bytes(bytes(corrupted))
        try:
            with warnings.catch_warnings():
                warnings.filterwarnings("ignore", "dropped", UserWarning)
                strands = load_hair(path)
        except HairFormatError as error:
            assert str(error).startswith(f"{path}: ")
        else:
            assert np.isfinite(strands.points).all()
