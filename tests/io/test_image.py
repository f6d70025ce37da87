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
