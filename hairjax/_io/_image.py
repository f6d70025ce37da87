"""Image files through OpenImageIO: EXR float for data, PNG 8-bit sRGB for viewing.

Writes are atomic (`_files.atomic_path`): an error never leaves a half-written file.
`read_image` is the one reader of every image the package takes (fit targets and masks,
`hairjax view`): strict (a damaged file is an error naming it, never zeros) and with one
rule for alpha (read as stored, never applied to the colours).
"""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from ._files import atomic_path

__all__ = [
    "write_image",
    "write_png_codes",
    "read_image",
    "linear_to_srgb",
    "srgb_to_linear",
    "srgb8",
    "ImageError",
]


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
    _write(path, data, fmt)
    return path


def write_png_codes(path, codes) -> Path:
    """Write `uint8 [H, W, 1|3|4]` codes to the PNG `path` as they are (display values
    already, e.g. a false-colour map), atomically. ImageError for another type or shape."""
    path = Path(path)
    codes = np.asarray(codes)
    if codes.dtype != np.uint8 or codes.ndim != 3 or codes.shape[2] not in (1, 3, 4):
        raise ImageError(f"{path}: expected uint8 [H, W, 1|3|4] codes, got {codes.dtype} {codes.shape}")
    if path.suffix.lower() != ".png":
        raise ImageError(f"{path}: 8-bit codes are written as .png, got {path.suffix!r}")
    _write(path, codes, "uint8")
    return path


def _write(path: Path, data: np.ndarray, fmt: str) -> None:
    """`data` `[H, W, C]` to `path` through OpenImageIO in `fmt`, atomically."""
    import OpenImageIO as oiio

    with atomic_path(path, path.suffix.lower()) as tmp:
        h, w, c = data.shape
        spec = oiio.ImageSpec(w, h, c, fmt)
        out = oiio.ImageOutput.create(tmp)
        if out is None or not out.open(tmp, spec):
            raise ImageError(f"{path}: cannot open for writing: {oiio.geterror()}")
        ok = out.write_image(np.ascontiguousarray(data))
        ok = out.close() and ok
        if not ok:
            raise ImageError(f"{path}: write failed: {out.geterror() or oiio.geterror()}")


def read_image(path, *, decode_srgb: bool = True) -> np.ndarray:
    """Read an image file as float32 `[H, W, C]`, strictly: its first subimage, every
    channel, through the file type's own decoder (OpenImageIO).

    - Colour: a file of integer codes (8- or 16-bit PNG, TIFF) holds sRGB-encoded colour,
      decoded here to linear; a float file (EXR half or float, float TIFF) is linear and
      read as stored. `decode_srgb=False` returns every channel as stored, codes scaled
      to 0 … 1 (a mask's values, which are not colours).
    - Alpha: read as stored and never applied to the colour channels (no premultiplying
      on read, OpenImageIO's `oiio:UnassociatedAlpha`; no dividing either), so the colour
      channels of an RGBA file are those of the same image saved as RGB.
    - A decoder error, truncated data or a missing chunk is an `ImageError` naming the
      file; the decoders' own messages never reach stdout or stderr.
    """
    path = Path(path)
    if path.is_dir():
        raise ImageError(f"{path}: is a directory, not an image file")
    if not path.is_file():
        raise ImageError(f"{path}: no such file")
    with _native_output_silenced():
        data, integer, alpha = _decode(path)
    if decode_srgb and integer:
        colour = [c for c in range(data.shape[2]) if c != alpha]
        data[..., colour] = srgb_to_linear(data[..., colour])
    return data


def _decode(path: Path) -> tuple[np.ndarray, bool, int]:
    """(pixels `[H, W, C]` float32, whether the file holds integer codes, the alpha
    channel's index or −1), or `ImageError` with the decoder's first message. The error
    state is read after the pixels: OpenEXR reports missing scanline chunks, and libpng a
    truncated stream, only then (OpenEXR's rows then read as zeros)."""
    import OpenImageIO as oiio

    config = oiio.ImageSpec()
    config.attribute("oiio:UnassociatedAlpha", 1)  # colour as stored: alpha is not applied
    inp = oiio.ImageInput.open(str(path), config)
    if inp is None:
        raise ImageError(f"{path}: cannot read: {_first_line(oiio.geterror())}")
    try:
        spec = inp.spec()
        pixels = inp.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
        failed = pixels is None or inp.has_error
        message = inp.geterror() if inp.has_error else ""  # read, so OIIO prints nothing later
    finally:
        inp.close()
    if failed:
        raise ImageError(f"{path}: cannot read: {_first_line(message or oiio.geterror())}")
    data = np.array(pixels, dtype=np.float32).reshape(spec.height, spec.width, spec.nchannels)
    integer = spec.format.basetype in (oiio.UINT8, oiio.UINT16)
    return data, integer, spec.alpha_channel


def _first_line(message: str) -> str:
    lines = [line.strip() for line in message.splitlines() if line.strip()]
    return lines[0] if lines else "the decoder gave no reason"


@contextlib.contextmanager
def _native_output_silenced() -> Iterator[None]:
    """File descriptors 1 and 2 pointed at the null device while the decoders run: libpng
    prints its errors to stderr itself, besides reporting them through OpenImageIO's
    `geterror`, which `_decode` turns into the one message. Restored on exit; a
    descriptor that is not open is left alone."""
    import ctypes

    for stream in (sys.stdout, sys.stderr):
        if stream is not None:
            stream.flush()
    saved: dict[int, int] = {}
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        for fd in (1, 2):
            with contextlib.suppress(OSError):  # fires when the descriptor is closed
                saved[fd] = os.dup(fd)
                os.dup2(null, fd)
        yield
    finally:
        ctypes.CDLL(None).fflush(None)  # C stdio's buffers go to the null device, not later
        for fd, copy in saved.items():
            os.dup2(copy, fd)
            os.close(copy)
        os.close(null)
