"""A mask image as per-pixel weights of a fit's target (docs/fitting.md, "Target images
and masks").

The rule: the weight is the mask's alpha channel where it has one (grey + alpha, RGBA)
and that alpha is not 1 everywhere (a cut-out: the matte is its alpha), else its first
channel (a painted mask, white on black, opaque or without alpha). Values are read as
stored (`read_image(decode_srgb=False)`: an 8-bit code 255 is 1, 128 is 0.502, with no
sRGB decoding, since a mask is not a colour). 0 leaves a pixel out of the fit, 1 counts
it fully, and values between weigh its squared residual (a matte's soft edge). Values
outside 0 … 1, NaN, or a mask that is 0 everywhere are refused, naming the file.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ._image import ImageError, read_image

__all__ = ["read_mask"]


def read_mask(path) -> np.ndarray:
    """The weights `[H, W]` (float64, 0 … 1) of the mask image `path`, by the rule above.

    **Raises:** `ImageError` naming the file when it cannot be read (`read_image`), or
    when its weights are not finite, fall outside 0 … 1, or are 0 everywhere."""
    path = Path(path)
    data = read_image(path, decode_srgb=False)
    weights = data[..., 0].astype(np.float64)
    if data.shape[2] in (2, 4) and not np.all(data[..., -1] == 1):  # a cut-out's alpha
        weights = data[..., -1].astype(np.float64)
    if not np.all(np.isfinite(weights)):
        raise ImageError(f"{path}: the mask has NaN or infinite values; a mask's values are 0 … 1")
    low, high = float(weights.min()), float(weights.max())
    if low < 0 or high > 1:
        raise ImageError(f"{path}: the mask's values span {low:.6g} … {high:.6g}; a mask's values are 0 … 1")
    if high == 0:
        raise ImageError(f"{path}: the mask is 0 everywhere, which leaves no pixel to fit")
    return weights
