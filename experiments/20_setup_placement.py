"""The set-up on the host against the set-up on the device: the same fragments and the
same images (docs/model.md §5, `hairjax/_geometry/_device_raster.py`).

    python experiments/20_setup_placement.py --json out/setup_placement.json

For each scene of `experiments/scenes/` and the built-in default scene, renders it with
the set-up's rasters and grouping as compiled loops on the host (`HAIRJAX_SETUP=host`)
and as XLA programs on JAX's default device (`HAIRJAX_SETUP=device`; on a machine without
an accelerator that device is the CPU, which runs the same programs a GPU would), and
prints the largest absolute difference of the RGBA images (held to 1e-5, the bound
between two renders of one model), whether the camera's fragments are the same, and the
median time of a warm render of each (`--repeats`). A scene whose hair file is missing
is reported and skipped. About 2 minutes on this 2-core CPU at `--repeats 1`.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

import hairjax as hj

ROOT = Path(__file__).resolve().parents[1]
SCENES = sorted((ROOT / "experiments" / "scenes").glob("*.toml")) + [
    ROOT / "hairjax" / "scenes" / "default.toml"
]
TOLERANCE = 1e-5  # the bound between two renders of one model (docs/model.md)
PLACEMENTS = ("host", "device")


def render_on(scene: hj.Scene, where: str, repeats: int):
    """(image, camera fragments as NumPy, median seconds of `repeats` warm renders) with
    the set-up placed `where`. Each render takes a fresh copy of `scene`: the set-up is
    cached per scene object."""
    os.environ[hj.SETUP_PLACEMENT] = where
    fresh = scene.replace()
    image = np.asarray(hj.render(fresh))  # the warm-up: compiles
    setup = hj.prepare(fresh)
    fragments = tuple(np.asarray(x) for x in (setup.frag_pixel, setup.frag_i0, setup.frag_t))
    seconds = []
    for _ in range(repeats):
        again = scene.replace()
        start = time.perf_counter()
        np.asarray(hj.render(again))
        seconds.append(time.perf_counter() - start)
    return image, fragments, statistics.median(seconds) if seconds else None


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scenes", nargs="*", type=Path, help="scene files (default: every example scene)")
    p.add_argument("--repeats", type=int, default=1, help="warm renders timed per placement (default 1)")
    p.add_argument("--json", type=Path, help="also write the table as JSON")
    args = p.parse_args(argv)
    before = os.environ.get(hj.SETUP_PLACEMENT)
    rows, worst = {}, 0.0

    def save() -> None:  # after every scene: a run stopped early keeps what it measured
        if args.json is not None:
            args.json.parent.mkdir(parents=True, exist_ok=True)
            data = {"tolerance": TOLERANCE, "scenes": rows, "worst": worst}
            args.json.write_text(json.dumps(data, indent=1))

    try:
        for path in args.scenes or SCENES:
            try:
                scene = hj.load_scene(path)
            except (OSError, hj.SceneError) as err:  # a hair file not on this machine
                rows[path.stem] = {"skipped": str(err)}
                print(f"{path.stem:20s} skipped: {err}", flush=True)
                save()
                continue
            out = {where: render_on(scene, where, args.repeats) for where in PLACEMENTS}
            (host_image, host_frags, host_s), (dev_image, dev_frags, dev_s) = out["host"], out["device"]
            diff = float(np.abs(host_image - dev_image).max())
            same = all(a.shape == b.shape and np.array_equal(a, b) for a, b in zip(host_frags, dev_frags))
            worst = max(worst, diff)
            rows[path.stem] = {
                "max_abs": diff,
                "same_fragments": same,
                "fragments": int(host_frags[0].size),
                "host_s": host_s,
                "device_s": dev_s,
            }
            timing = "" if host_s is None else f"   host {host_s:.3f} s, device {dev_s:.3f} s"
            print(
                f"{path.stem:20s} max |host - device| {diff:.3g}   fragments "
                f"{'same' if same else 'DIFFER'} ({host_frags[0].size:,}){timing}",
                flush=True,
            )
            save()
    finally:
        if before is None:
            os.environ.pop(hj.SETUP_PLACEMENT, None)
        else:
            os.environ[hj.SETUP_PLACEMENT] = before
    ok = worst <= TOLERANCE
    print(f"largest difference {worst:.3g} ({'within' if ok else 'OVER'} {TOLERANCE:g})")
    save()
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
