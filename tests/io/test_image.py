"""Image files (hairjax/_io/_image.py): EXR keeps float32 data bit for bit, PNG is 8-bit
sRGB of the linear values for viewing, other types and shapes are refused naming the
file, and a write that fails leaves no file behind (hairjax/_io/_files.py's atomic_path).

The PNG's bytes are read back through OpenImageIO as raw 8-bit codes and compared with
the sRGB curve written out here, so the writer and its test do not share the encoder."""

from __future__ import annotations

import os
import sys
import types

import numpy as np
import OpenImageIO as oiio
import pytest

import hairjax as hj
from hairjax._io._image import ImageError, linear_to_srgb, srgb_to_linear

EXR_MAGIC = b"\x76\x2f\x31\x01"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def srgb_by_hand(x: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1's encoding of linear [0, 1] (clipped), in float64."""
    x = np.clip(np.asarray(x, np.float64), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)


def raw_codes(path) -> np.ndarray:
    buf = oiio.ImageBuf(str(path))
    assert buf.spec().format == oiio.UINT8
    return np.asarray(buf.get_pixels(oiio.UINT8))


def wide_range_image(shape, seed=0) -> np.ndarray:
    """float32 values over 40 decades, both signs, with exact zeros and values above 1."""
    rng = np.random.default_rng(seed)
    x = rng.normal(size=shape) * 10.0 ** rng.uniform(-20, 20, shape)
    x.flat[::7] = 0.0
    return x.astype(np.float32)


# --------------------------------------------------------------------------- EXR


@pytest.mark.parametrize("channels", [1, 3, 4])
def test_exr_round_trip_is_bit_exact_in_float32(tmp_path, channels):
    image = wide_range_image((5, 7, channels), seed=channels)
    path = hj.write_image(tmp_path / "a.exr", image)
    assert path == tmp_path / "a.exr" and path.read_bytes()[:4] == EXR_MAGIC
    back = hj.read_image(path)
    assert back.dtype == np.float32 and back.shape == (5, 7, channels)
    np.testing.assert_array_equal(back.view(np.uint32), image.view(np.uint32))


def test_exr_of_float64_data_is_its_float32_rounding(tmp_path):
    image = np.random.default_rng(1).uniform(0.0, 1.0, (4, 3, 4))  # float64, as renders are
    back = hj.read_image(hj.write_image(tmp_path / "r.EXR", image))  # the suffix in any case
    np.testing.assert_array_equal(back.view(np.uint32), image.astype(np.float32).view(np.uint32))
    assert not np.array_equal(back.astype(np.float64), image)  # rounded: float64 did not survive


# --------------------------------------------------------------------------- PNG


def test_png_is_8_bit_srgb_of_the_linear_values(tmp_path):
    # Every 8-bit step's neighbourhood, the linear segment near 0, and values outside [0, 1].
    x = np.concatenate(
        [np.linspace(0.0, 1.0, 1021), np.geomspace(1e-6, 0.0031308, 40), [-0.5, -1e-9, 1.0 + 1e-9, 3.0]]
    )
    rgba = np.zeros((len(x), 3, 4))
    rgba[:, 0, :3] = x[:, None]
    rgba[:, 1, :3] = x[::-1, None]
    rgba[:, 2, :3] = np.stack([x, x[::-1], np.roll(x, 5)], axis=1)
    rgba[..., 3] = 0.25  # alpha, which the PNG drops
    path = hj.write_image(tmp_path / "view.png", rgba)
    assert path.read_bytes()[:8] == PNG_MAGIC
    codes = raw_codes(path)
    assert codes.shape == (len(x), 3, 3)  # RGB only
    expected = srgb_by_hand(rgba[..., :3].astype(np.float32))
    # Rounding to the nearest code: within half a step (the float32 curve adds ~1e-7).
    assert np.abs(codes / 255.0 - expected).max() <= 0.5 / 255 + 1e-6
    assert codes[x == 0.0, 0].max() == 0 and codes[x >= 1.0, 0].min() == 255
    assert codes[x < 0, 0].max() == 0  # negatives clip to black
    # read_image decodes the codes back to linear.
    np.testing.assert_allclose(hj.read_image(path), srgb_to_linear(codes / 255.0), rtol=1e-6, atol=1e-7)


def test_png_of_one_channel_is_grey(tmp_path):
    grey = np.linspace(0.0, 1.0, 12).reshape(3, 4, 1)
    codes = raw_codes(hj.write_image(tmp_path / "g.png", grey))
    assert codes.shape == (3, 4, 1)
    np.testing.assert_array_equal(codes, np.round(srgb_by_hand(grey) * 255))


def test_srgb_curve_matches_the_standard_and_inverts():
    x = np.linspace(0.0, 1.0, 2001)
    np.testing.assert_allclose(linear_to_srgb(x), srgb_by_hand(x), rtol=1e-15, atol=1e-16)
    np.testing.assert_allclose(srgb_to_linear(linear_to_srgb(x)), x, rtol=1e-12, atol=1e-15)
    # The standard's two thresholds (0.0031308 linear, 0.04045 encoded) disagree in the 7th
    # digit: just above the first, the code falls below the second and decodes through the
    # linear piece. The round trip is off there by that much, and no more.
    edge = np.array([0.0031308, np.nextafter(0.0031308, 1.0), 0.00313085])
    np.testing.assert_allclose(linear_to_srgb(edge), srgb_by_hand(edge), rtol=1e-15)
    np.testing.assert_allclose(srgb_to_linear(linear_to_srgb(edge)), edge, rtol=1e-6)
    assert abs(12.92 * 0.0031308 - (1.055 * 0.0031308 ** (1 / 2.4) - 0.055)) < 1e-7


# --------------------------------------------------------------------------- errors


@pytest.mark.parametrize("name", ["image.bmpx", "image.jpg", "image"])
def test_an_unsupported_type_is_an_error_naming_the_path(tmp_path, name):
    path = tmp_path / name
    with pytest.raises(ImageError, match=rf"^{path}: unsupported image type '.*' \(use .exr or .png\)$"):
        hj.write_image(path, np.zeros((2, 2, 4)))
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("shape", [(4, 4), (4, 4, 2), (1, 4, 4, 4)])
def test_a_shape_that_is_not_an_image_is_an_error_naming_the_path(tmp_path, shape):
    path = tmp_path / "a.exr"
    with pytest.raises(ImageError, match=rf"^{path}: expected an \[H, W, 1\|3\|4\] image"):
        hj.write_image(path, np.zeros(shape))
    assert os.listdir(tmp_path) == []


def test_reading_a_missing_or_broken_file_is_an_error_naming_it(tmp_path):
    missing = tmp_path / "none.exr"
    with pytest.raises(ImageError, match=rf"^{missing}: no such file$"):
        hj.read_image(missing)
    broken = tmp_path / "broken.exr"
    broken.write_bytes(EXR_MAGIC + b"not an image")
    with pytest.raises(ImageError, match=rf"^{broken}: cannot read"):
        hj.read_image(broken)
    assert issubclass(ImageError, OSError)


def test_reading_a_directory_says_it_is_one(tmp_path):
    folder = tmp_path / "target.png"
    folder.mkdir()
    with pytest.raises(ImageError, match=rf"^{folder}: is a directory, not an image file$"):
        hj.read_image(folder)


def failing_oiio(written: list, fail_by: str):
    """A stand-in for OpenImageIO whose write puts half the bytes into the file it was
    given, then fails: by returning False (as OIIO does on a full disk) or by raising."""
    real = oiio

    class Output:
        def __init__(self, name):
            self.name = name

        def open(self, name, spec):
            return True

        def write_image(self, data):
            with open(self.name, "wb") as f:
                f.write(data.tobytes()[: data.nbytes // 2])
            written.append(self.name)
            if fail_by == "raise":
                raise RuntimeError("interrupted")
            return False

        def close(self):
            return True

        def geterror(self):
            return "no space left on device"

    fake = types.SimpleNamespace(
        ImageSpec=real.ImageSpec, geterror=lambda: "", ImageOutput=types.SimpleNamespace(create=Output)
    )
    return fake


@pytest.mark.parametrize("fail_by", ["return", "raise"])
@pytest.mark.parametrize("name", ["a.exr", "a.png"])
def test_a_failed_write_leaves_no_partial_file(tmp_path, monkeypatch, fail_by, name):
    target = tmp_path / "out" / name
    before = hj.write_image(tmp_path / "out" / "kept.exr", np.ones((2, 2, 4)))
    written = []
    monkeypatch.setitem(sys.modules, "OpenImageIO", failing_oiio(written, fail_by))
    error = (
        (ImageError, rf"^{target}: write failed: no space left on device$")
        if fail_by == "return"
        else (RuntimeError, "interrupted")
    )
    with pytest.raises(error[0], match=error[1]):
        hj.write_image(target, np.full((8, 8, 4), 0.5))
    # The half-written bytes went to a temporary beside the target, which is gone.
    assert len(written) == 1 and os.path.dirname(written[0]) == str(target.parent)
    assert os.path.basename(written[0]) != name and not os.path.exists(written[0])
    assert sorted(os.listdir(target.parent)) == ["kept.exr"]
    monkeypatch.undo()
    np.testing.assert_array_equal(hj.read_image(before), 1.0)


def test_a_failed_rewrite_keeps_the_old_file(tmp_path, monkeypatch):
    target = hj.write_image(tmp_path / "a.exr", np.full((2, 3, 4), 0.25))
    old = target.read_bytes()
    monkeypatch.setitem(sys.modules, "OpenImageIO", failing_oiio([], "return"))
    with pytest.raises(ImageError, match="write failed"):
        hj.write_image(target, np.zeros((2, 3, 4)))
    assert target.read_bytes() == old and os.listdir(tmp_path) == ["a.exr"]


def test_writing_makes_the_folder_and_replaces_an_old_file(tmp_path):
    target = tmp_path / "new" / "deeper" / "a.exr"
    hj.write_image(target, np.zeros((2, 2, 3)))
    hj.write_image(target, np.full((2, 2, 3), 2.0))
    np.testing.assert_array_equal(hj.read_image(target), 2.0)
    assert os.listdir(target.parent) == ["a.exr"]  # no temporary left behind


# --------------------------------------------------------------------------- reading each type
#
# The files below are written by OpenImageIO's writers from codes and values chosen here,
# and the expected linear values follow from the standard's decoding written out by hand
# (`linear_by_hand`), not from the reader under test.


def linear_by_hand(encoded: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1's decoding of sRGB values in [0, 1], in float64."""
    v = np.asarray(encoded, np.float64)
    return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)


def oiio_write(path, data: np.ndarray, fmt: str, unassociated: bool = False):
    """`data` `[H, W, C]` written by OpenImageIO's own writer for `path`'s type, in `fmt`.
    `unassociated`: the colour channels are stored as given beside the alpha (OIIO's
    writers otherwise divide colour by alpha, taking the data to be premultiplied)."""
    h, w, c = data.shape
    spec = oiio.ImageSpec(w, h, c, fmt)
    if unassociated:
        spec.attribute("oiio:UnassociatedAlpha", 1)
    out = oiio.ImageOutput.create(str(path))
    assert out is not None and out.open(str(path), spec), oiio.geterror()
    assert out.write_image(np.ascontiguousarray(data)), out.geterror()
    assert out.close()
    return path


def codes(shape, top: int, seed: int = 0) -> np.ndarray:
    """Integer codes 0 … top, both ends included."""
    rng = np.random.default_rng(seed)
    c = rng.integers(0, top + 1, size=shape)
    c.flat[0], c.flat[-1] = 0, top
    return c.astype(np.uint8 if top == 255 else np.uint16)


@pytest.mark.parametrize("name, top", [("a.png", 255), ("a.png", 65535), ("a.tif", 255), ("a.tif", 65535)])
def test_integer_files_are_srgb_decoded(tmp_path, name, top):
    c = codes((5, 7, 3), top)
    path = oiio_write(tmp_path / name, c, "uint8" if top == 255 else "uint16")
    back = hj.read_image(path)
    assert back.dtype == np.float32 and back.shape == (5, 7, 3)
    # float32 decoding of the float64 curve: a few float32 ulps of values ≤ 1.
    np.testing.assert_allclose(back, linear_by_hand(c / top), rtol=1e-6, atol=1e-7)


@pytest.mark.parametrize("name, fmt", [("a.exr", "half"), ("a.exr", "float"), ("a.tif", "float")])
def test_float_files_are_linear_as_stored(tmp_path, name, fmt):
    values = np.random.default_rng(3).uniform(-0.5, 4.0, (6, 4, 4)).astype(np.float32)
    path = oiio_write(tmp_path / name, values, fmt)
    expected = values.astype(np.float16).astype(np.float32) if fmt == "half" else values
    back = hj.read_image(path)
    assert back.dtype == np.float32
    np.testing.assert_array_equal(back, expected)  # no curve, no alpha applied: bit for bit


@pytest.mark.parametrize("name, top", [("a.png", 255), ("a.png", 65535), ("a.tif", 255)])
def test_rgba_colour_reads_as_the_same_image_saved_rgb(tmp_path, name, top):
    """An alpha channel changes nothing in the colour channels (OpenImageIO's default
    would premultiply a PNG's or TIFF's colour by its alpha on read), and the alpha itself
    is read as stored, not sRGB-decoded."""
    fmt = "uint8" if top == 255 else "uint16"
    rgb = codes((6, 8, 3), top, seed=1)
    alpha = codes((6, 8, 1), top, seed=2)  # 0 (transparent) … top, and all between
    plain = hj.read_image(oiio_write(tmp_path / f"rgb{name}", rgb, fmt))
    with_alpha = hj.read_image(
        oiio_write(tmp_path / f"rgba{name}", np.concatenate([rgb, alpha], -1), fmt, True)
    )
    assert with_alpha.shape == (6, 8, 4)
    np.testing.assert_array_equal(with_alpha[..., :3], plain)
    np.testing.assert_allclose(with_alpha[..., 3], alpha[..., 0] / top, rtol=1e-6)


def test_rgba_png_stores_what_the_fixture_says(tmp_path):
    """The fixture's RGBA PNG holds the colour codes as given: Pillow (another decoder,
    which does not premultiply) reads them back, so the test above compares like with like."""
    import io

    from PIL import Image

    rgba = np.concatenate([codes((3, 4, 3), 255, seed=5), codes((3, 4, 1), 255, seed=6)], -1)
    path = oiio_write(tmp_path / "x.png", rgba, "uint8", True)
    with Image.open(io.BytesIO(path.read_bytes())) as im:
        np.testing.assert_array_equal(np.asarray(im.convert("RGBA")), rgba)


def test_grey_and_alpha_decodes_the_grey_only(tmp_path):
    c = codes((4, 5, 2), 255, seed=4)
    back = hj.read_image(oiio_write(tmp_path / "ga.png", c, "uint8", True))
    np.testing.assert_allclose(back[..., 0], linear_by_hand(c[..., 0] / 255), rtol=1e-6, atol=1e-7)
    np.testing.assert_allclose(back[..., 1], c[..., 1] / 255, rtol=1e-6)


def test_decode_srgb_false_reads_codes_as_stored(tmp_path):
    c = codes((3, 3, 3), 65535, seed=7)
    back = hj.read_image(oiio_write(tmp_path / "m.png", c, "uint16"), decode_srgb=False)
    np.testing.assert_allclose(back, c / 65535, rtol=1e-6)


# --------------------------------------------------------------------------- damaged files


def damaged(tmp_path, kind: str):
    """A file OpenImageIO wrote, then damaged: cut to two thirds (its last rows' chunks
    missing), or with bytes of its pixel data overwritten."""
    image = np.random.default_rng(8).uniform(0.0, 1.0, (64, 64, 3)).astype(np.float32)
    if kind.endswith("exr"):
        whole = oiio_write(tmp_path / "whole.exr", image, "half")
    else:
        whole = oiio_write(tmp_path / "whole.png", np.round(image * 255).astype(np.uint8), "uint8")
    data = bytearray(whole.read_bytes())
    if kind.startswith("truncated"):
        data = data[: len(data) * 2 // 3]
    else:  # corrupted: the middle of the pixel data zeroed
        data[len(data) // 2 : len(data) // 2 + 64] = bytes(64)
    path = tmp_path / f"{kind}{whole.suffix}"
    path.write_bytes(bytes(data))
    return path


DAMAGED = ["truncated-exr", "truncated-png", "corrupted-exr", "corrupted-png"]


@pytest.mark.parametrize("kind", DAMAGED)
def test_a_damaged_file_is_refused_in_one_line_and_silently(tmp_path, capfd, kind):
    """Read on main, a truncated EXR gave zeros for its missing rows (and OpenImageIO
    printed "Some scanline chunks were missing or corrupted" to stdout at exit), a
    truncated PNG its rows as decoded so far (and libpng wrote to stderr)."""
    path = damaged(tmp_path, kind)
    with pytest.raises(ImageError) as info:
        hj.read_image(path)
    message = str(info.value)
    assert message.startswith(f"{path}: cannot read: ") and "\n" not in message
    import gc

    gc.collect()  # any object OIIO would print an unread error from, at its destruction
    assert capfd.readouterr() == ("", "")


@pytest.mark.parametrize("name, fmt", [("f.exr", "half"), ("f.png", "uint8"), ("f.tif", "uint16")])
def test_corrupted_files_fuzzed_give_an_image_or_one_line(tmp_path, capfd, name, fmt):
    """Seeded corruptions (cuts, flipped bytes, zeroed runs) of a whole file: each read
    gives a float32 image of the file's shape or one ImageError line naming it, and no
    decoder prints anything. (Neither format checksums all its data, so a flipped byte can
    decode to other pixels; what must not happen is a crash, another exception or noise.)"""
    rng = np.random.default_rng(11)
    values = rng.uniform(0, 1, (16, 12, 3))
    data = values.astype(np.float32) if fmt == "half" else np.round(values * 255).astype(np.uint8)
    whole = bytearray(oiio_write(tmp_path / name, data, fmt).read_bytes())
    path = tmp_path / f"fuzzed{os.path.splitext(name)[1]}"
    outcomes = set()
    for _ in range(40):
        damaged_bytes = bytearray(whole)
        kind = int(rng.integers(3))
        at = int(rng.integers(len(whole)))
        if kind == 0:
            damaged_bytes = damaged_bytes[:at]
        elif kind == 1:
            damaged_bytes[at] ^= 1 << int(rng.integers(8))
        else:
            damaged_bytes[at : at + 16] = bytes(len(damaged_bytes[at : at + 16]))
        path.write_bytes(bytes(damaged_bytes))
        try:
            image = hj.read_image(path)
        except ImageError as err:
            assert str(err).startswith(f"{path}: ") and "\n" not in str(err)
            outcomes.add("refused")
        else:
            assert image.dtype == np.float32 and image.shape == (16, 12, 3)
            outcomes.add("read")
    assert "refused" in outcomes
    assert capfd.readouterr() == ("", "")


def test_reading_with_stdout_and_stderr_closed(tmp_path):
    """A process whose descriptors 1 and 2 are closed still reads (nothing to silence)."""
    import subprocess

    path = oiio_write(tmp_path / "a.png", np.full((2, 2, 3), 128, np.uint8), "uint8")
    code = (
        "import os, sys, hairjax as hj; os.close(1); os.close(2); "
        f"sys.exit(0 if hj.read_image({str(path)!r}).shape == (2, 2, 3) else 5)"
    )
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    assert subprocess.run([sys.executable, "-c", code], env=env).returncode == 0
