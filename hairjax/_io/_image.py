"""Image files through OpenImageIO: EXR float for data, PNG 8-bit sRGB for viewing.

Writes are atomic (`_files.atomic_path`): an error never leaves a half-written file.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ._files import atomic_path

__all__ = ["write_image", "read_image", "linear_to_srgb", "srgb_to_linear", "srgb8", "ImageError"]


class ImageError(OSError):
    """An image could not be read or written; the message names the file."""


def linear_to_srgb(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def srgb8(x: np.ndarray) -> np.ndarray:
    """Linear values (clipped to 0 … 1) as 8-bit sRGB, rounded to the nearest code: what a
    PNG holds. Every channel given is encoded; pick the colour channels first."""
    return np.round(np.clip(linear_to_srgb(np.asarray(x)), 0, 1) * 255).astype(np.uint8)


def srgb_to_linear(x: np.ndarray) -> np.ndarray:
    return np.where(x <= 0.04045, x / 12.92, np.power((x + 0.055) / 1.055, 2.4))


def write_image(path, image) -> Path:
    """Write `[H, W, C]` linear float data: `.exr` as float32 (all channels), `.png` as
    8-bit sRGB RGB for viewing (the renderer's RGB already includes the background, so the
    PNG drops alpha and shows what a viewer expects)."""
    import OpenImageIO as oiio

    path = Path(path)
    image = np.asarray(image, dtype=np.float32)
    if image.ndim != 3 or image.shape[2] not in (1, 3, 4):
        raise ImageError(f"{path}: expected an [H, W, 1|3|4] image, got shape {image.shape}")
    suffix = path.suffix.lower()
    if suffix == ".exr":
        data, fmt = image, "float"
    elif suffix == ".png":
        data = srgb8(image[..., :3] if image.shape[2] >= 3 else image)
        fmt = "uint8"
    else:
        raise ImageError(f"{path}: unsupported image type {suffix!r} (use .exr or .png)")
    with atomic_path(path, suffix) as tmp:
        h, w, c = data.shape
        spec = oiio.ImageSpec(w, h, c, fmt)
        out = oiio.ImageOutput.create(tmp)
        if out is None or not out.open(tmp, spec):
            raise ImageError(f"{path}: cannot open for writing: {oiio.geterror()}")
        ok = out.write_image(np.ascontiguousarray(data))
        ok = out.close() and ok
        if not ok:
            raise ImageError(f"{path}: write failed: {out.geterror() or oiio.geterror()}")
    return path


def read_image(path) -> np.ndarray:
    """Read an image as linear float32 `[H, W, C]` (PNG/8-bit colour decoded from sRGB)."""
    import OpenImageIO as oiio

    path = Path(path)
    if path.is_dir():
        raise ImageError(f"{path}: is a directory, not an image file")
    if not path.is_file():
        raise ImageError(f"{path}: no such file")
    buf = oiio.ImageBuf(str(path))
    if buf.has_error:
        raise ImageError(f"{path}: cannot read: {buf.geterror()}")
    data = np.asarray(buf.get_pixels(oiio.FLOAT), dtype=np.float32)
    if data.ndim == 2:
        data = data[..., None]
    if buf.spec().format.basetype in (oiio.UINT8, oiio.UINT16):
        c = min(data.shape[2], 3)
        data[..., :c] = srgb_to_linear(data[..., :c])
    return data
