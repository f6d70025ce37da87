"""The same images on every device and from either set-up: the JAX renderer on JAX's
default device (a GPU where there is one) against the same renderer on the CPU, its
set-up on the host against its set-up on the device, and the GL renderer against both, on
every example scene (BENCHMARKS.md, "GPU: one NVIDIA H200" and "The set-up on the device,
built").

    python experiments/19_device_images.py --json out/device_images.json
    python experiments/19_device_images.py --repeats 3 --json out/device_images.json   # with timings

For each scene of `experiments/scenes/` and the built-in default scene it prints the
largest absolute difference of the RGBA images: default device against the CPU (docs/model.md
holds them to 1e-5: float32 arithmetic in another order, and a GPU's scatter-add in no
fixed order); the set-up's rasters and grouping as compiled loops on the host
(`placement="host"`) against XLA programs on the default device (`"device"`, docs/model.md
§5; on a machine without an accelerator that device is the CPU, which runs the programs a
GPU would), with whether their camera fragments are the same and, with `--repeats N`, the
median time of N warm renders of each; and GL against the default device's JAX (the bands
docs/model.md §11 explains). A scene whose hair file is missing is reported and skipped.
On a machine with no accelerator both JAX images come from the CPU and must be equal.
About 3 minutes on this 2-core CPU at `--repeats 3`.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

import jax
import numpy as np

import hairjax as hj

ROOT = Path(__file__).resolve().parents[1]
SCENES = sorted((ROOT / "experiments" / "scenes").glob("*.toml")) + [
    ROOT / "hairjax" / "scenes" / "default.toml"
]
TOLERANCE = 1e-5  # between two renders of one model: experiments/README.md row 19, docs/model.md §5


def jax_image(path: Path, device) -> np.ndarray:
    """A fresh scene (the geometry stage is cached per scene object) rendered on `device`."""
    with jax.default_device(device):
        return np.asarray(hj.render(hj.load_scene(path)))


def placed_render(path: Path, where: str, repeats: int):
    """(image, camera fragments as NumPy, median seconds of `repeats` warm renders or None)
    with the set-up placed `where`; every render on a fresh scene (the set-up is cached
    per scene object)."""
    scene = hj.load_scene(path)
    image = np.asarray(hj.render(scene, placement=where))  # the warm-up: compiles
    setup = hj.experimental.prepare(scene, placement=where)
    fragments = tuple(np.asarray(x) for x in (setup.frag_pixel, setup.frag_i0, setup.frag_t))
    seconds = []
    for _ in range(repeats):
        again = scene.replace()
        start = time.perf_counter()
        np.asarray(hj.render(again, placement=where))
        seconds.append(time.perf_counter() - start)
    return image, fragments, statistics.median(seconds) if seconds else None


def setup_row(path: Path, repeats: int) -> dict:
    """The host set-up against the device set-up on one scene."""
    (host, host_frags, host_s), (device, device_frags, device_s) = (
        placed_render(path, where, repeats) for where in ("host", "device")
    )
    return {
        "max_abs": float(np.abs(host - device).max()),
        "same_fragments": all(
            a.shape == b.shape and np.array_equal(a, b) for a, b in zip(host_frags, device_frags)
        ),
        "fragments": int(host_frags[0].size),
        "host_s": host_s,
        "device_s": device_s,
    }


def write_images(folder: Path, name: str, jax_image: np.ndarray, gl: np.ndarray | None) -> None:
    """`NAME_jax.exr`, and where GL ran `NAME_gl.exr` and `NAME_diff.exr` (|GL − JAX|)."""
    folder.mkdir(parents=True, exist_ok=True)
    hj.write_image(folder / f"{name}_jax.exr", jax_image)
    if gl is not None:
        hj.write_image(folder / f"{name}_gl.exr", gl)
        hj.write_image(folder / f"{name}_diff.exr", np.abs(gl - jax_image))


def gl_image(path: Path) -> np.ndarray | None:
    from hairjax.gl import GLUnavailable, render_gl

    try:
        return np.asarray(render_gl(hj.load_scene(path)).image)
    except GLUnavailable:
        return None


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scenes", nargs="*", type=Path, help="scene files (default: every example scene)")
    p.add_argument("--repeats", type=int, default=0, help="warm renders timed per set-up placement")
    p.add_argument("--json", type=Path, help="also write the differences as JSON")
    p.add_argument(
        "--images",
        type=Path,
        help="also write each scene's JAX and GL images and |GL − JAX| (EXR) into this folder: "
        "the evidence for a GL difference beyond its band on a new driver",
    )
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
        setup = setup_row(path, args.repeats)
        gl = gl_image(path)
        if args.images is not None:
            write_images(args.images, path.stem, on_default, gl)
        device_diff = float(np.abs(on_default - on_cpu).max())
        gl_diff = None if gl is None else float(np.abs(gl - on_default).max())
        worst = max(worst, device_diff, setup["max_abs"])
        rows[path.stem] = {"device_vs_cpu": device_diff, "gl_vs_device": gl_diff, "setup": setup}
        gl_text = "GL unavailable" if gl_diff is None else f"GL vs JAX {gl_diff:.3g}"
        timing = "" if setup["host_s"] is None else f" ({setup['host_s']:.3f} s / {setup['device_s']:.3f} s)"
        print(
            f"{path.stem:20s} {default.platform} vs cpu {device_diff:.3g}   host vs device set-up "
            f"{setup['max_abs']:.3g}, fragments {'same' if setup['same_fragments'] else 'DIFFER'}"
            f"{timing}   {gl_text}",
            flush=True,
        )
        save()
    ok = worst <= TOLERANCE
    print(f"largest difference {worst:.3g} ({'within' if ok else 'OVER'} {TOLERANCE:g})")
    save()
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
