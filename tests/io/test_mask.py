"""A mask image as a fit's weights (hairjax/_io/_mask.py): alpha when it has a matte,
else the first channel; values as stored (no sRGB curve); refused, naming the file, when
out of 0 … 1, NaN, 0 everywhere or unreadable. Files are written by OpenImageIO's own
writers from values chosen here."""

from __future__ import annotations

import re

import numpy as np
import OpenImageIO as oiio
import pytest

from hairjax._io._image import ImageError
from hairjax._io._mask import read_mask


def oiio_write(path, data: np.ndarray, fmt: str):
    h, w, c = data.shape
    spec = oiio.ImageSpec(w, h, c, fmt)
    spec.attribute("oiio:UnassociatedAlpha", 1)  # colour stored as given beside alpha
    out = oiio.ImageOutput.create(str(path))
    assert out is not None and out.open(str(path), spec), oiio.geterror()
    assert out.write_image(np.ascontiguousarray(data)) and out.close()
    return path


def test_a_grey_png_is_its_codes_over_255_not_srgb_decoded(tmp_path):
    grey = np.array([[0, 64, 128, 255]], np.uint8)[..., None]
    weights = read_mask(oiio_write(tmp_path / "m.png", grey, "uint8"))
    assert weights.shape == (1, 4) and weights.dtype == np.float64
    # 128 → 0.502, where sRGB decoding would give 0.216.
    np.testing.assert_allclose(weights, [[0, 64 / 255, 128 / 255, 1]], rtol=1e-6)


def test_an_opaque_rgba_mask_uses_its_first_channel(tmp_path):
    rgba = np.zeros((2, 3, 4), np.uint8)
    rgba[..., 0] = [[255, 0, 255], [0, 0, 255]]  # painted in red, green and blue ignored
    rgba[..., 1] = 77
    rgba[..., 3] = 255
    weights = read_mask(oiio_write(tmp_path / "m.png", rgba, "uint8"))
    np.testing.assert_array_equal(weights, [[1, 0, 1], [0, 0, 1]])


@pytest.mark.parametrize("channels", [2, 4])
def test_a_cut_out_uses_its_alpha(tmp_path, channels):
    data = np.full((2, 2, channels), 200, np.uint16)  # the photograph's colour, ignored
    data[..., -1] = [[0, 65535], [32768, 65535]]
    weights = read_mask(oiio_write(tmp_path / "m.png", data, "uint16"))
    np.testing.assert_allclose(weights, [[0, 1], [32768 / 65535, 1]], rtol=1e-9)


def test_an_exr_mask_is_its_values(tmp_path):
    values = np.array([[0.0, 0.25], [0.75, 1.0]], np.float32)[..., None]
    np.testing.assert_array_equal(read_mask(oiio_write(tmp_path / "m.exr", values, "float")), values[..., 0])


@pytest.mark.parametrize(
    "values, message",
    [
        ([[0.0, 1.5]], "the mask's values span 0 … 1.5; a mask's values are 0 … 1"),
        ([[-0.25, 1.0]], "the mask's values span -0.25 … 1; a mask's values are 0 … 1"),
        ([[np.nan, 1.0]], "the mask has NaN or infinite values; a mask's values are 0 … 1"),
        ([[0.0, 0.0]], "the mask is 0 everywhere, which leaves no pixel to fit"),
    ],
)
def test_bad_values_are_refused_naming_the_file(tmp_path, values, message):
    path = oiio_write(tmp_path / "m.exr", np.asarray(values, np.float32)[..., None], "float")
    with pytest.raises(ImageError, match="^" + re.escape(f"{path}: {message}") + "$"):
        read_mask(path)


def test_an_unreadable_mask_is_refused_naming_the_file(tmp_path):
    whole = oiio_write(tmp_path / "whole.png", np.full((32, 32, 1), 255, np.uint8), "uint8")
    cut = tmp_path / "cut.png"
    cut.write_bytes(whole.read_bytes()[:60])
    with pytest.raises(ImageError, match=f"^{re.escape(str(cut))}: cannot read: "):
        read_mask(cut)
