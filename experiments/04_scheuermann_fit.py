"""Fit the Scheuermann model's parameters to a rendered target (docs/model.md §17).

The target is rendered from hidden parameters — by GL (`--target gl`, the default) or
JAX — on experiments/scenes/scheuermann.toml's settings at a smaller size; `hairjax.fit`
(Levenberg-Marquardt on the shading stage, the geometry stage once) starts from a point
20-100 % off and recovers Kd (RGB), both highlights' colours, exponents and shifts.

    .venv/bin/python experiments/04_scheuermann_fit.py [--size 96] [--strands 1000] [--target jax]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import jax
import numpy as np

import hairjax as hj

SCENE = Path(__file__).resolve().parent / "scenes" / "scheuermann.toml"
TRUE = dict(
    kd=(0.42, 0.27, 0.16),
    primary_color=0.25,
    primary_exponent=120.0,
    primary_shift=0.1,
    secondary_color=0.3,
    secondary_exponent=25.0,
    secondary_shift=-0.15,
)
START = dict(
    kd=(0.3, 0.3, 0.3),
    primary_color=0.15,
    primary_exponent=70.0,
    primary_shift=0.0,
    secondary_color=0.2,
    secondary_exponent=40.0,
    secondary_shift=-0.05,
)
NAMES = tuple(TRUE)


def scene_at(size: int, strands: int) -> hj.Scene:
    """The example scene's settings with `strands` strands at `size`²."""
    scene = hj.load_scene(SCENE)
    hair = hj.scalp(
        strands=strands,
        points=12,
        seed=2,
        length=1.0,
        gravity=(0.0, -0.5, 0.0),
        radius=0.5,
        coverage=0.6,
        alpha=0.6,
    )
    cam = scene.camera
    return scene.replace(
        strands=hair,
        camera=hj.Camera(eye=cam.eye, target=cam.target, fov=cam.fov, width=size, height=size),
        shadows=hj.Shadows("opacity-maps", maps=16, resolution=size),
    )


def params_of(values: dict, base: hj.ScheuermannParams) -> hj.ScheuermannParams:
    fields = {k: getattr(base, k) for k in ("ambient", "kappa")}
    return hj.ScheuermannParams(**fields, **values)


def relative_errors(fitted: dict, truth: dict) -> dict:
    return {
        k: float(np.max(np.abs(np.asarray(fitted[k]) - np.asarray(truth[k])) / np.abs(np.asarray(truth[k]))))
        for k in truth
    }


def run(size: int = 96, strands: int = 1000, target: str = "gl", max_steps: int = 100):
    """Returns (relative errors by name, steps, seconds after the geometry stage, RMSE)."""
    scene = scene_at(size, strands)
    truth = params_of(TRUE, scene.params)
    geometry = hj.geometry_stage(scene)
    if target == "gl":
        from hairjax.gl import occluder_light, render_gl

        # Ω and the occluder's light from the JAX geometry stage, so only the camera pass
        # differs (float32 shading).
        image = render_gl(
            scene, truth, omega=np.asarray(geometry.omega), occluder=occluder_light(scene, geometry)
        ).image
    else:
        image = np.asarray(hj.shading_stage(geometry, truth))
    result = hj.fit(
        scene,
        image,
        init=params_of(START, scene.params),
        variables=NAMES,
        stop=hj.FitStop(max_steps=max_steps),
    )
    fitted = {n: getattr(result.params, n) for n in NAMES}
    return relative_errors(fitted, TRUE), result.steps, result.time_s, result.rmse


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--size", type=int, default=96)
    p.add_argument("--strands", type=int, default=1000)
    p.add_argument("--target", choices=("gl", "jax"), default="gl")
    args = p.parse_args(argv)
    jax.config.update("jax_enable_x64", True)
    errors, steps, seconds, rmse = run(args.size, args.strands, args.target)
    print(
        f"Scheuermann fit to a {args.target.upper()} target, {args.size}², {args.strands} strands: "
        f"{steps} LM steps, {seconds:.1f} s, RMSE {rmse:.2e}"
    )
    for name, err in errors.items():
        print(f"  {name:20s} relative error {err:.2e}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
