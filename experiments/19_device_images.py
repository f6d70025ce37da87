"""The same images on every device: the JAX renderer on JAX's default device (a GPU where
there is one) against the same renderer on the CPU, and the GL renderer against both, on
every example scene (BENCHMARKS.md, "GPU: one NVIDIA H200").

    python experiments/19_device_images.py --json out/device_images.json

For each scene of `experiments/scenes/` and the built-in default scene it prints the
largest absolute difference of the RGBA images: default device against the CPU (docs/model.md
holds them to 1e-5: float32 arithmetic in another order, and a GPU's scatter-add in no
fixed order), and GL against the default device's JAX (the bands docs/model.md §11
explains). A scene whose hair file is missing is reported and skipped. On a machine with
no accelerator both JAX images come from the CPU and must be equal. About 1 minute on
this 2-core CPU.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import jax
import numpy as np

import hairjax as hj

ROOT = Path(__file__).resolve().parents[1]
SCENES = sorted((ROOT / "experiments" / "scenes").glob("*.toml")) + [
    ROOT / "hairjax" / "scenes" / "default.toml"
]
TOLERANCE = 1e-5  # the bound between two renders of one model (docs/model.md)


def jax_image(path: Path, device) -> np.ndarray:
    """A fresh scene (the geometry stage is cached per scene object) rendered on `device`."""
    with jax.default_device(device):
        return np.asarray(hj.render(hj.load_scene(path)))


def gl_image(path: Path) -> np.ndarray | None:
    from hairjax.gl import GLUnavailable, render_gl

    try:
        return np.asarray(render_gl(hj.load_scene(path)).image)
    except GLUnavailable:
        return None


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scenes", nargs="*", type=Path, help="scene files (default: every example scene)")
    p.add_argument("--json", type=Path, help="also write the differences as JSON")
    args = p.parse_args(argv)
    default, cpu = jax.devices()[0], jax.devices("cpu")[0]
    print(f"default device {default} against {cpu}", flush=True)
    rows, worst = {}, 0.0

    def save() -> None:  # after every scene: a run stopped early keeps what it measured
        if args.json is not None:
            args.json.parent.mkdir(parents=True, exist_ok=True)
            data = {"default_device": str(default), "tolerance": TOLERANCE, "scenes": rows, "worst": worst}
            args.json.write_text(json.dumps(data, indent=1))

    for path in args.scenes or SCENES:
        try:
            on_default, on_cpu = jax_image(path, default), jax_image(path, cpu)
        except (OSError, hj.SceneError) as err:  # a hair file not on this machine
            rows[path.stem] = {"skipped": str(err)}
            print(f"{path.stem:20s} skipped: {err}", flush=True)
            save()
            continue
        gl = gl_image(path)
        device_diff = float(np.abs(on_default - on_cpu).max())
        gl_diff = None if gl is None else float(np.abs(gl - on_default).max())
        worst = max(worst, device_diff)
        rows[path.stem] = {"device_vs_cpu": device_diff, "gl_vs_device": gl_diff}
        gl_text = "GL unavailable" if gl_diff is None else f"GL vs JAX {gl_diff:.3g}"
        print(f"{path.stem:20s} {default.platform} vs cpu {device_diff:.3g}   {gl_text}", flush=True)
        save()
    ok = worst <= TOLERANCE
    print(f"largest device difference {worst:.3g} ({'within' if ok else 'OVER'} {TOLERANCE:g})")
    save()
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
