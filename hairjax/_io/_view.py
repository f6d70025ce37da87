"""Looking at images: linear renders tone-mapped to 8-bit sRGB, and a fit shown beside
its target with the residual between them.

- `tonemap(image, exposure)`: linear RGB(A) → uint8, the PNG writer's encode after a gain
  of 2^exposure;
- `tonemap_file(src, dst, exposure)`: an EXR (or any image `read_image` takes) to a PNG;
- `side_by_side(target, fitted, path)`: a PNG of three panels, target | fit | residual,
  the residual fitted − target as a signed map with a colour bar and its RMSE.

NumPy and matplotlib only (the Agg canvas, no pyplot state); matplotlib is imported when
a figure is drawn, so importing this module stays light.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ._files import atomic_path
from ._image import ImageError, read_image, srgb8, write_image

__all__ = ["tonemap", "tonemap_file", "residual", "side_by_side_figure", "side_by_side"]


def _image(name: str, image) -> np.ndarray:
    a = np.asarray(image, np.float64)
    if a.ndim != 3 or a.shape[2] not in (3, 4):
        raise ValueError(f"{name} must be an [H, W, 3|4] image, got shape {a.shape}")
    return a


def _gain(exposure: float) -> float:
    if not math.isfinite(exposure):
        raise ValueError(f"exposure must be a finite number of stops, got {exposure!r}")
    return 2.0**exposure


def tonemap(image, exposure: float = 0.0) -> np.ndarray:
    """Linear `[H, W, 3|4]` float → `uint8` of the same shape: RGB times 2^exposure, then
    the PNG writer's 8-bit sRGB encode (`srgb8`: clipped to 0 … 1). Alpha is coverage, not
    light: it is not exposed nor sRGB-encoded, only clipped and rounded to 8 bits.
    NaN pixels show black."""
    a = _image("image", image)
    out = np.empty(a.shape, np.uint8)
    out[..., :3] = srgb8(np.nan_to_num(a[..., :3] * _gain(exposure), nan=0.0))
    if a.shape[2] == 4:
        out[..., 3] = np.round(np.clip(np.nan_to_num(a[..., 3], nan=0.0), 0, 1) * 255).astype(np.uint8)
    return out


def tonemap_file(src, dst, exposure: float = 0.0) -> Path:
    """Write the image file `src` (linear, e.g. an EXR render) as the 8-bit sRGB PNG `dst`,
    its RGB times 2^exposure first; atomically, as every image write."""
    dst = Path(dst)
    if dst.suffix.lower() != ".png":
        raise ImageError(f"{dst}: the tone-mapped image is a .png, got {dst.suffix!r}")
    image = _image(str(src), read_image(src))
    return write_image(dst, image[..., :3] * _gain(exposure))


def residual(target, fitted) -> tuple[np.ndarray, float]:
    """(map, rmse) of fitted − target over RGB: `map` the per-pixel mean of the three
    channels' differences `[H, W]` (signed: positive where the fit is brighter), `rmse`
    over all RGB values, linear. Alpha is not compared."""
    t, f = _image("target", target), _image("fitted", fitted)
    if t.shape[:2] != f.shape[:2]:
        raise ValueError(f"target and fitted differ in size: {t.shape[:2]} against {f.shape[:2]}")
    d = f[..., :3] - t[..., :3]
    return d.mean(axis=-1), float(np.sqrt(np.mean(d**2)))


def side_by_side_figure(target, fitted, *, exposure: float = 0.0, title: str | None = None):
    """A matplotlib `Figure` (Agg canvas): target | fit | residual, the two images
    tone-mapped at `exposure`, the residual (`residual`) on a diverging scale symmetric
    about 0 with its colour bar and, in its panel's title, its RMSE."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    diff, rmse = residual(target, fitted)
    h, w = diff.shape
    panel = 3.0  # inches per panel's height
    fig = Figure(figsize=(3 * panel * w / h + 1.0, panel + (0.9 if title else 0.6)), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, 3)
    for ax, image, name in zip(axes[:2], (target, fitted), ("target", "fit")):
        ax.imshow(tonemap(image, exposure)[..., :3], interpolation="nearest")
        ax.set_title(name if exposure == 0 else f"{name} ({exposure:+g} EV)")
    # Symmetric about 0 so white is "no difference"; identical images get a tiny range, a
    # uniform white panel rather than matplotlib's degenerate-scale warning.
    limit = max(float(np.abs(diff).max(initial=0.0)), 1e-12)
    shown = axes[2].imshow(diff, cmap="RdBu_r", vmin=-limit, vmax=limit, interpolation="nearest")
    axes[2].set_title(f"residual fit − target, RMSE {rmse:.3g}")
    fig.colorbar(shown, ax=axes[2], shrink=0.85, label="RGB mean, linear")
    for ax in axes:
        ax.set_axis_off()
    if title:
        fig.suptitle(title)
    return fig


def side_by_side(target, fitted, path, *, exposure: float = 0.0, title: str | None = None) -> Path:
    """Write `side_by_side_figure` as the PNG `path`, atomically. Returns `path`."""
    path = Path(path)
    fig = side_by_side_figure(target, fitted, exposure=exposure, title=title)
    with atomic_path(path, ".png") as tmp:
        fig.savefig(tmp, format="png", dpi=100)
    return path
