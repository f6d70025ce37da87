"""`hairjax compare`: render a scene with both renderers and measure how they differ,
against the band of pixels where the model explains a difference (docs/model.md §11)."""

from __future__ import annotations

import dataclasses
import numbers
import statistics
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import jax
import numpy as np

from .._cache import forget
from .._disagreement import PIXEL_TOL, renderer_band
from .._geometry_stage._stage import geometry_stage
from .._io._image import linear_to_srgb, write_image, write_png_codes
from .._progress import Progress, counter
from .._render import render
from .._scene._scene import Scene

__all__ = [
    "compare",
    "image_stats",
    "band_verdict",
    "verdict_text",
    "difference_image",
    "write_difference",
    "format_report",
    "check_repeats",
    "median_time",
    "timed_calls",
    "TimedCalls",
]

# The difference image's colours (8-bit sRGB display values, not linear light): pixels
# that differ inside the explained band, and outside it.
IN_BAND_COLOUR = (0.25, 0.55, 1.0)  # blue
OUTSIDE_COLOUR = (1.0, 0.35, 0.0)  # orange-red
AGREE_GREY = 0.35  # the JAX render's grey, dimmed, where the two agree


def image_stats(a: np.ndarray, b: np.ndarray) -> dict:
    """Max abs difference, RMSE, PSNR (peak 1) and the share of pixels differing by more
    than PIXEL_TOL in any channel, between two `[H, W, C]` images."""
    d = np.abs(np.asarray(a, np.float64) - np.asarray(b, np.float64))
    mse = float(np.mean(d**2))
    return {
        "max_abs": float(d.max(initial=0.0)),
        "rmse": mse**0.5,
        "psnr_db": float("inf") if mse == 0 else float(-10 * np.log10(mse)),
        "share_over_1e-4": float(np.mean(d.max(axis=-1) > PIXEL_TOL)),
    }


def _differing(gl_image: np.ndarray, jax_image: np.ndarray) -> np.ndarray:
    """`[H, W]` max over RGB of |GL − JAX| (float64)."""
    d = np.abs(np.asarray(gl_image, np.float64)[..., :3] - np.asarray(jax_image, np.float64)[..., :3])
    return d.max(axis=-1)


def band_verdict(scene: Scene, gl_image: np.ndarray, jax_image: np.ndarray) -> tuple[dict, np.ndarray]:
    """({"band_share", "differing", "outside_band"}, band `bool[H, W]`): the share of pixels
    in `renderer_band` (colour bound: JAX's brightest RGB value, as its tests take it), how
    many pixels differ by more than PIXEL_TOL in any RGB channel, and how many of those lie
    outside the band, where the model explains no difference (docs/model.md §11)."""
    jax_rgb = np.asarray(jax_image, np.float64)[..., :3]
    band = renderer_band(scene, colour_bound=float(jax_rgb.max(initial=0.0)))
    differ = _differing(gl_image, jax_image) > PIXEL_TOL
    verdict = {
        "band_share": float(band.mean()),
        "differing": int(np.count_nonzero(differ)),
        "outside_band": int(np.count_nonzero(differ & ~band)),
    }
    return verdict, band


def difference_image(gl_image: np.ndarray, jax_image: np.ndarray, band: np.ndarray) -> np.ndarray:
    """`uint8[H, W, 3]` sRGB, one pixel per rendered pixel: where GL and JAX agree within
    PIXEL_TOL, the JAX render in grey, dimmed (for orientation); where they differ, blue
    inside `band` and orange-red outside it, brighter the larger the difference
    d = max over RGB of |GL − JAX|: 40 % at d = 1e-4 rising to full at d = 1, on a log
    scale (README, `hairjax compare --diff`)."""
    d = _differing(gl_image, jax_image)
    jax_rgb = np.clip(np.nan_to_num(np.asarray(jax_image, np.float64)[..., :3]), 0.0, 1.0)
    grey = AGREE_GREY * linear_to_srgb(jax_rgb.mean(axis=-1))
    out = np.repeat(grey[..., None], 3, axis=-1)
    differ = d > PIXEL_TOL
    # log10(d / 1e-4) / 4: 0 at the tolerance, 1 at d = 1; the clip fires above 1.
    level = 0.4 + 0.6 * np.clip(np.log10(np.where(differ, d, PIXEL_TOL) / PIXEL_TOL) / 4.0, 0.0, 1.0)
    for where, colour in ((differ & band, IN_BAND_COLOUR), (differ & ~band, OUTSIDE_COLOUR)):
        out[where] = level[where, None] * np.asarray(colour)
    return np.round(out * 255).astype(np.uint8)


def write_difference(path, gl_image: np.ndarray, jax_image: np.ndarray, band: np.ndarray) -> Path:
    """Write the difference of the two renders to `path`, atomically: a `.png` is
    `difference_image`; an `.exr` the signed GL − JAX of every channel, linear float32."""
    path = Path(path)
    if path.suffix.lower() == ".exr":
        return write_image(path, np.asarray(gl_image, np.float64) - np.asarray(jax_image, np.float64))
    return write_png_codes(path, difference_image(gl_image, jax_image, band))


def check_repeats(repeats) -> int:
    """`repeats` as an int, or ValueError when it is not a positive integer (a median of
    no timings does not exist: refused before any rendering starts)."""
    if isinstance(repeats, bool) or not isinstance(repeats, numbers.Integral) or repeats < 1:
        raise ValueError(f"repeats must be a positive integer, got {repeats!r}")
    return int(repeats)


@dataclasses.dataclass(frozen=True)
class TimedCalls:
    """`timed_calls`' record: `warm_up_s`, the first call's seconds (compilation, shader
    builds, caches: not in the median); `runs_s`, each timed call's seconds; `last`, the
    last call's result."""

    warm_up_s: float
    runs_s: list[float]
    last: Any

    @property
    def median_s(self) -> float:
        return statistics.median(self.runs_s)


def _timed_call(fn) -> tuple[float, Any]:
    """(seconds, result) of one call of `fn`, its result waited for: JAX dispatches work
    asynchronously, so a call returns before its arrays are computed."""
    start = time.perf_counter()
    result = jax.block_until_ready(fn())
    return time.perf_counter() - start, result


def timed_calls(fn, repeats: int, after: Callable[[int, Any, float], None] | None = None) -> TimedCalls:
    """One warm-up call of `fn`, then `repeats` timed calls; each call's result is waited for
    with `jax.block_until_ready` within its timed span (leaves without the method, e.g. NumPy
    arrays or a GL result, are returned as they are).

    `after(k, result, seconds)`, when given, runs after call k (0 the warm-up), outside the
    timed span. A call's result is dropped before the next call starts, so that two calls'
    arrays never coexist; `TimedCalls.last` keeps the last one."""
    repeats = check_repeats(repeats)
    warm_up_s, result = _timed_call(fn)
    if after is not None:
        after(0, result, warm_up_s)
    runs_s = []
    for k in range(1, repeats + 1):
        del result
        seconds, result = _timed_call(fn)
        runs_s.append(seconds)
        if after is not None:
            after(k, result, seconds)
    return TimedCalls(warm_up_s=warm_up_s, runs_s=runs_s, last=result)


def median_time(fn, repeats: int, after: Callable[[int], None] | None = None) -> float:
    """Median wall time of `repeats` calls of `fn`, after one warm-up call (`timed_calls`:
    each result waited for with `jax.block_until_ready`).

    `after(k)`, when given, runs after call k (0 the warm-up), outside the timed span."""
    report = None if after is None else (lambda k, _result, _seconds: after(k))
    return timed_calls(fn, repeats, report).median_s


def compare(scene: Scene, repeats: int = 3, *, progress: Progress | None = None, diff=None) -> dict:
    """Render with JAX and GL, and report image and τ differences, the verdict against
    the explained band (`band_verdict`) and median timings.

    `progress(done, total, message)` after each render: the two compared renders, then
    each renderer's warm-up and `repeats` timed runs (2 + 2·(1 + repeats) steps).
    `diff`: a `.png` or `.exr` path to write the two renders' difference to
    (`write_difference`), before the timings.

    **Raises:** ValueError when `repeats` is not a positive integer, before rendering."""
    from ..gl import render_gl

    repeats = check_repeats(repeats)
    step = counter(2 + 2 * (1 + repeats), progress)

    def timing(name: str) -> Callable[[int], None]:
        return lambda k: step(f"{name} warm-up" if k == 0 else f"{name} timed run {k}/{repeats}")

    jax_image = np.asarray(render(scene))
    step("jax render")
    gl = render_gl(scene)
    step("gl render")
    stats = image_stats(gl.image, jax_image)
    verdict, band = band_verdict(scene, gl.image, jax_image)
    if diff is not None:
        write_difference(diff, gl.image, jax_image, band)
    tau_diff = None
    if gl.omega is not None:
        kappa = float(scene.params.kappa)
        # τ = exp(−κΩ) (`transmittance`, §7) in float64 NumPy, as the sweep measures it.
        jax_tau = np.exp(-kappa * np.asarray(geometry_stage(scene).omega, np.float64))
        gl_tau = np.exp(-kappa * gl.omega.astype(np.float64))
        tau_diff = float(np.abs(jax_tau - gl_tau).max(initial=0.0))

    def jax_full():
        forget(scene)
        jax.block_until_ready(render(scene))

    return {
        "scene": scene.name,
        "size": [scene.camera.width, scene.camera.height],
        **stats,
        **verdict,
        "tau_max_abs": tau_diff,
        "jax_s": median_time(jax_full, repeats, timing("jax")),
        "gl_s": median_time(lambda: render_gl(scene), repeats, timing("gl")),
        "repeats": repeats,
    }


def verdict_text(r: dict) -> str:
    """The verdict line's text: "within band" when every pixel differing by more than
    PIXEL_TOL lies in the explained band, else how many lie outside it."""
    share = f"the band holds {100 * r['band_share']:.2f} % of pixels, docs/model.md §11"
    if r["differing"] == 0:
        return f"within band (no pixel differs by > 1e-4; {share})"
    if r["outside_band"] == 0:
        return f"within band (all {r['differing']} pixels differing by > 1e-4 lie in it; {share})"
    pixels = r["size"][0] * r["size"][1]
    return (
        f"{r['outside_band']} pixels ({100 * r['outside_band'] / pixels:.4f} %) differ by > 1e-4 "
        f"outside the explained band ({share})"
    )


def format_report(r: dict) -> str:
    # GL reports no Ω without shadows, and for hair patches (it shades them with JAX's colours).
    # τ = exp(−κΩ) (docs/model.md §7): the share of the light that reaches a strand point
    # through the hair between it and the light, 0 (fully shadowed) to 1 (fully lit).
    tau = (
        "n/a (no Ω from GL)"
        if r["tau_max_abs"] is None
        else f"{r['tau_max_abs']:.3g}  (largest JAX−GL difference in τ, the share of light reaching "
        "a strand point through the hair, 0 to 1; docs/model.md §7)"
    )
    return "\n".join(
        [
            f"{r['scene']} ({r['size'][0]}x{r['size'][1]}): GL vs JAX",
            f"  max abs difference   {r['max_abs']:.3g}",
            f"  RMSE                 {r['rmse']:.3g}",
            f"  PSNR                 {r['psnr_db']:.1f} dB",
            f"  pixels > 1e-4        {100 * r['share_over_1e-4']:.4f} %",
            f"  max |Δτ| per point   {tau}",
            f"  verdict              {verdict_text(r)}",
            f"  time, JAX (full)     {r['jax_s']:.3f} s  (median of {r['repeats']})",
            f"  time, GL             {r['gl_s']:.3f} s  (ratio JAX/GL {r['jax_s'] / r['gl_s']:.2f})",
        ]
    )
