"""`hairjax compare`: render a scene with both renderers and measure how they differ."""

from __future__ import annotations

import numbers
import statistics
import time
from collections.abc import Callable

import jax
import numpy as np

from .._cache import forget
from .._disagreement import PIXEL_TOL
from .._geometry._stage import geometry_stage
from .._progress import Progress
from .._render import render
from .._scene._scene import Scene

__all__ = ["compare", "image_stats", "format_report", "check_repeats", "median_time"]


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


def check_repeats(repeats) -> int:
    """`repeats` as an int, or ValueError when it is not a positive integer (a median of
    no timings does not exist: refused before any rendering starts)."""
    if isinstance(repeats, bool) or not isinstance(repeats, numbers.Integral) or repeats < 1:
        raise ValueError(f"repeats must be a positive integer, got {repeats!r}")
    return int(repeats)


def median_time(fn, repeats: int, after: Callable[[int], None] | None = None) -> float:
    """Median wall time of `repeats` calls of `fn`, after one untimed call.

    `after(k)`, when given, runs after call k (0 the warm-up), outside the timed span."""
    repeats = check_repeats(repeats)
    fn()  # warm-up: compilation, shader builds, caches
    if after is not None:
        after(0)
    times = []
    for k in range(1, repeats + 1):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
        if after is not None:
            after(k)
    return statistics.median(times)


def compare(scene: Scene, repeats: int = 3, *, progress: Progress | None = None) -> dict:
    """Render with JAX and GL, and report image and τ differences and median timings.

    `progress(done, total, message)` after each render: the two compared renders, then
    each renderer's warm-up and `repeats` timed runs (2 + 2·(1 + repeats) steps).

    **Raises:** ValueError when `repeats` is not a positive integer, before rendering."""
    from ..gl import render_gl

    repeats = check_repeats(repeats)
    total = 2 + 2 * (1 + repeats)
    done = 0

    def step(message: str) -> None:
        nonlocal done
        done += 1
        if progress is not None:
            progress(done, total, message)

    def timing(name: str) -> Callable[[int], None]:
        return lambda k: step(f"{name} warm-up" if k == 0 else f"{name} timed run {k}/{repeats}")

    jax_image = np.asarray(render(scene))
    step("jax render")
    gl = render_gl(scene)
    step("gl render")
    stats = image_stats(gl.image, jax_image)
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
        "tau_max_abs": tau_diff,
        "jax_s": median_time(jax_full, repeats, timing("jax")),
        "gl_s": median_time(lambda: render_gl(scene), repeats, timing("gl")),
        "repeats": repeats,
    }


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
            f"  time, JAX (full)     {r['jax_s']:.3f} s  (median of {r['repeats']})",
            f"  time, GL             {r['gl_s']:.3f} s  (ratio JAX/GL {r['jax_s'] / r['gl_s']:.2f})",
        ]
    )
