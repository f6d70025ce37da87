"""Time a 4-parameter fit to 1e-3 relative error, staged vs two baselines (BENCHMARKS.md, "Fitting").

- staged: `hairjax.fit` (geometry stage once, Levenberg-Marquardt on the shading stage);
- (a) `scipy.optimize.least_squares` with finite differences over GL renders;
- (b) JAX autodiff (the same optimistix LM) but re-running the whole renderer, NumPy
  set-up included, at every evaluation — no staging.

All three start from the same point and stop at convergence with the same tolerances
(float32: relative 1e-5, absolute 1e-7); the table gives the time
after the first geometry stage, the steps, the worst relative error, and the ratios.

    .venv/bin/python experiments/02_fit_speed.py [--size 512] [--strands 20000]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time

import numpy as np

import hairjax as hj
from hairjax.gl import render_gl

TRUE = hj.ShadingParams(kd=(0.45, 0.3, 0.2), ks=0.35, shininess=60.0, kappa=3.0, ambient=0.05)
START = hj.ShadingParams(kd=0.6, ks=0.2, shininess=30.0, kappa=1.5, ambient=0.05)
NAMES = ("kd", "ks", "shininess", "kappa")


def worst_error(params) -> float:
    return max(
        float(
            np.max(
                np.abs(np.asarray(getattr(params, n)) - np.asarray(getattr(TRUE, n)))
                / np.abs(np.asarray(getattr(TRUE, n)))
            )
        )
        for n in NAMES
    )


def vector(p) -> np.ndarray:
    return np.concatenate(
        [
            np.log(np.asarray(p.kd)),
            np.log(np.asarray(p.ks)),
            [np.log(float(p.shininess)), np.log(float(p.kappa))],
        ]
    )


def params_of(v) -> hj.ShadingParams:
    v = np.exp(v)
    return hj.ShadingParams(kd=v[:3], ks=v[3:6], shininess=v[6], kappa=v[7], ambient=TRUE.ambient)


def staged(scene, target):
    r = hj.fit(scene, target, init=START)  # Levenberg-Marquardt
    return r.time_s, r.steps, worst_error(r.params)


def scipy_gl(scene, target):
    from scipy.optimize import least_squares

    rgb = target[..., :3].ravel()
    calls = [0]

    def residual(v):
        calls[0] += 1
        return render_gl(scene, params_of(v)).image[..., :3].ravel() - rgb

    start = time.perf_counter()
    # The same tolerances as the staged fit in float32 (hairjax.fit's defaults).
    r = least_squares(residual, vector(START), method="lm", x_scale=1.0, xtol=1e-5, ftol=1e-7)
    # Every residual evaluation is one GL render (finite-difference columns included).
    return time.perf_counter() - start, f"{calls[0]} renders", worst_error(params_of(r.x))


def unstaged(scene, target):
    """optimistix LM, eager, every evaluation a whole render (caches cleared)."""
    import jax
    import jax.numpy as jnp
    import optimistix as optx

    rgb = jnp.asarray(target[..., :3])

    def fn(v, args):
        hj.experimental.forget(scene)
        v = jnp.exp(v)
        p = hj.ShadingParams(kd=v[:3], ks=v[3:6], shininess=v[6], kappa=v[7], ambient=TRUE.ambient)
        return (hj.render(scene, p)[..., :3] - rgb).ravel()

    start = time.perf_counter()
    with jax.disable_jit():
        sol = optx.least_squares(
            fn,
            optx.LevenbergMarquardt(rtol=1e-5, atol=1e-7),
            jnp.asarray(vector(START)),
            max_steps=100,
            throw=False,
        )
    return (
        time.perf_counter() - start,
        int(sol.stats["num_steps"]),
        worst_error(params_of(np.asarray(sol.value))),
    )


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--size", type=int, default=512)
    p.add_argument("--strands", type=int, default=20000)
    p.add_argument("--skip", default="", help="comma-separated baselines to skip: scipy,unstaged")
    args = p.parse_args(argv)
    scene = hj.load_scene(hj.default_scene_path())
    scene = scene.replace(
        strands=hj.furball(args.strands, 16, alpha=0.5),
        camera=dataclasses.replace(scene.camera, width=args.size, height=args.size),
    )
    target_jax = np.asarray(hj.render(scene, TRUE))
    target_gl = render_gl(scene, TRUE).image
    # The first fit compiles the step functions; the second shows the warm cost.
    results = {
        "staged, first (compiles)": staged(scene, target_jax),
        "staged (hairjax.fit)": staged(scene, target_jax),
    }
    if "scipy" not in args.skip:
        results["(a) scipy FD over GL"] = scipy_gl(scene, target_gl)
    if "unstaged" not in args.skip:
        results["(b) JAX, unstaged"] = unstaged(scene, target_jax)
    base = results["staged (hairjax.fit)"][0]
    print(f"fur ball {args.strands} strands x 16 points at {args.size}^2, 4 parameters (8 values)")
    print(f"{'method':<24} {'time':>9} {'steps':>14} {'worst rel. err':>15} {'ratio':>8}")
    for name, (t, steps, err) in results.items():
        print(f"{name:<24} {t:8.2f}s {steps!s:>14} {err:15.2e} {t / base:7.1f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
