"""Viewing images (hairjax/_io/_view.py): the tone map against sRGB by hand, exposure as
a gain of 2^EV, alpha untouched; the EXR → PNG file path; the residual by hand; the
target | fit | residual PNG read back."""

from __future__ import annotations

import numpy as np
import pytest

from hairjax._io._image import ImageError, read_image, srgb8, write_image
from hairjax._io._view import residual, side_by_side, side_by_side_figure, tonemap, tonemap_file


def srgb_by_hand(x):
    """IEC 61966-2-1's encode, written out again here (not the package's)."""
    x = min(max(x, 0.0), 1.0)
    return 12.92 * x if x <= 0.0031308 else 1.055 * x ** (1 / 2.4) - 0.055


LINEAR = [0.0, 0.001, 0.0031308, 0.01, 0.05, 0.18, 0.5, 0.9, 1.0, 1.5, -0.2]


def test_tonemap_is_srgb_to_the_nearest_code():
    image = np.array(LINEAR, np.float64).reshape(1, -1, 1).repeat(3, axis=2)
    codes = tonemap(image)
    assert codes.dtype == np.uint8 and codes.shape == image.shape
    exact = np.array([255 * srgb_by_hand(x) for x in LINEAR])
    # 8-bit output: the nearest code is within half a code of the exact value, no closer.
    assert np.all(np.abs(codes[0, :, 0] - exact) <= 0.5)
    # A few by hand: 0.5 → 1.055·0.5^(1/2.4) − 0.055 = 0.73536 → 187.5 → 188; the ends clip.
    assert codes[0, LINEAR.index(0.5)].tolist() == [188] * 3
    assert codes[0, LINEAR.index(1.5)].tolist() == [255] * 3
    assert codes[0, LINEAR.index(-0.2)].tolist() == [0] * 3
    # The PNG writer's encode, not a second one.
    np.testing.assert_array_equal(codes, srgb8(image))


def test_exposure_is_a_gain_of_two_per_stop():
    rng = np.random.default_rng(0)
    image = rng.uniform(0, 0.6, (4, 5, 3))
    np.testing.assert_array_equal(tonemap(image, exposure=1.0), tonemap(2 * image))
    np.testing.assert_array_equal(tonemap(image, exposure=-2.0), tonemap(image / 4))
    assert tonemap(np.full((1, 1, 3), 0.25), exposure=1.0).tolist() == [[[188] * 3]]  # 0.5's code
    with pytest.raises(ValueError, match="exposure must be a finite number"):
        tonemap(image, exposure=float("nan"))


def test_alpha_passes_through_unexposed():
    image = np.zeros((2, 2, 4))
    image[..., :3] = 0.1
    image[..., 3] = [[0.2, 1.0], [0.0, 0.6]]
    for ev in (0.0, 3.0):
        out = tonemap(image, exposure=ev)
        # Coverage rounded to 8 bits, linear: 0.2·255 = 51, 0.6·255 = 153, both exact.
        assert out[..., 3].tolist() == [[51, 255], [0, 153]]
    assert tonemap(image, 3.0)[0, 0, 0] > tonemap(image)[0, 0, 0]  # the colour was exposed
    with pytest.raises(ValueError, match=r"\[H, W, 3\|4\] image"):
        tonemap(np.zeros((2, 2)))


def test_tonemap_file_writes_the_tonemapped_png(tmp_path):
    image = np.linspace(0, 0.7, 2 * 6 * 4).reshape(2, 6, 4).astype(np.float32)
    exr = write_image(tmp_path / "render.exr", image)
    png = tonemap_file(exr, tmp_path / "render.png", exposure=0.5)
    back = read_image(png)  # decoded from sRGB to linear
    assert back.shape == (2, 6, 3)
    # Re-encoding the decoded codes gives the codes again (float32 round trip ≪ half a code).
    np.testing.assert_array_equal(srgb8(back), tonemap(image, 0.5)[..., :3])
    with pytest.raises(ImageError, match=r"is a \.png"):
        tonemap_file(exr, tmp_path / "out.jpg")


def test_residual_by_hand():
    target = np.full((3, 4, 4), 0.25)
    fitted = target.copy()
    fitted[..., 0] += 0.1  # red brighter by 0.1 everywhere; alpha differences are ignored
    fitted[..., 3] = 0.0
    diff, rmse = residual(target, fitted)
    np.testing.assert_allclose(diff, 0.1 / 3, rtol=1e-12)
    assert rmse == pytest.approx(np.sqrt(0.1**2 / 3), rel=1e-12)
    assert residual(target, target) == (pytest.approx(np.zeros((3, 4))), 0.0)
    with pytest.raises(ValueError, match="differ in size"):
        residual(target, target[:2])


def test_side_by_side_png(tmp_path):
    h, w = 24, 24
    yy, xx = np.mgrid[0:h, 0:w]
    target = np.stack([xx / w, yy / h, 0.3 + 0 * xx, 1 + 0 * xx], axis=-1)
    fitted = target.copy()
    fitted[: h // 2, :, :3] *= 1.2
    path = side_by_side(target, fitted, tmp_path / "view" / "fit.png", title="a fit")
    assert path == tmp_path / "view" / "fit.png"
    assert sorted(p.name for p in path.parent.iterdir()) == ["fit.png"]  # no temporary left
    image = read_image(path)
    height, width = image.shape[:2]
    # Three square panels side by side, plus the colour bar: well over twice as wide as high.
    assert 2.5 * height < width < 4 * height, (width, height)
    assert np.ptp(image[..., :3]) > 0.5  # something drawn, not a blank canvas


def test_identical_images_have_a_zero_residual():
    target = np.random.default_rng(1).uniform(0, 1, (10, 14, 3))
    fig = side_by_side_figure(target, target.copy())
    titles = [ax.get_title() for ax in fig.axes[:3]]
    assert titles == ["target", "fit", "residual fit − target, RMSE 0"]
    fig = side_by_side_figure(target, target + 0.01, exposure=1.0)
    assert [ax.get_title() for ax in fig.axes[:3]] == [
        "target (+1 EV)",
        "fit (+1 EV)",
        "residual fit − target, RMSE 0.01",
    ]
