"""`hairjax compare`: render a scene with both renderers and measure how they differ."""

from __future__ import annotations

import statistics
import time

import jax
import numpy as np

from .._cache import forget
from .._disagreement import PIXEL_TOL
from .._geometry._stage import geometry_stage
from .._render import render
from .._scene._scene import Scene

__all__ = ["compare", "image_stats", "format_report"]


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


def median_time(fn, repeats: int) -> float:
    """Median wall time of `repeats` calls of `fn`, after one untimed call."""
    fn()  # warm-up: compilation, shader builds, caches
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def compare(scene: Scene, repeats: int = 3) -> dict:
    """Render with JAX and GL, and report image and τ differences and median timings."""
    from ..gl import render_gl

    jax_image = np.asarray(render(scene))
    gl = render_gl(scene)
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
        "jax_s": median_time(jax_full, repeats),
        "gl_s": median_time(lambda: render_gl(scene), repeats),
        "repeats": repeats,
    }


def format_report(r: dict) -> str:
    # GL reports no Ω without shadows, and for hair patches (it shades them with JAX's colours).
    tau = "n/a (no Ω from GL)" if r["tau_max_abs"] is None else f"{r['tau_max_abs']:.3g}"
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
