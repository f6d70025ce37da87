"""How long `hairjax.explore`'s panel takes to answer a slider (BENCHMARKS.md, "Live
exploration").

The panel keeps the geometry stage and re-runs only the shading stage when a shading
slider moves; a light slider re-runs the geometry stage too (the shadow maps are built
from the light). This measures, on the default scene at `--size`², the time from setting
a slider's `value` to the panel's image holding the new PNG (the slider's observer runs
synchronously, so that is the time of the assignment), as medians:

- `shading move`: `--moves` moves after 2 warm-up moves, cycling through Kd, Ks, the
  shininess and κ;
- of which `shading stage` (`hj.shading_stage` on the kept geometry, to the host) and
  `PNG` (`hj.write_image` of the RGB), timed alone the same number of times;
- `light move`: `--light-moves` azimuth moves after 1 warm-up move;
- `panel built`: `hj.explore(scene)` once (the first geometry stage and compilation).

    python experiments/10_explore_latency.py               # default scene, 256², 20 moves
    python experiments/10_explore_latency.py --quick       # tiny, for the test suite

Prints the table; `--json FILE` also writes the figures (seconds) and every move's time.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import platform
import statistics
import tempfile
import time
from pathlib import Path

import jax
import numpy as np

import hairjax as hj

SHADING_MOVES = (("kd", (0.3, 0.55)), ("ks", (0.6, 0.2)), ("shininess", (80.0, 20.0)), ("kappa", (0.5, 1.5)))
LIGHT_AZIMUTHS = (20.0, 80.0)


def bench_scene(size: int, quick: bool) -> hj.Scene:
    scene = hj.load_scene(hj.default_scene_path())
    scene = scene.replace(camera=dataclasses.replace(scene.camera, width=size, height=size))
    if quick:  # a few hundred strands: seconds, for the test suite; the figures mean nothing
        scene = scene.replace(strands=hj.furball(strands=300, points=8, seed=0, alpha=0.5))
    return scene


def timed(action) -> float:
    start = time.perf_counter()
    action()
    return time.perf_counter() - start


def measure(scene: hj.Scene, moves: int, light_moves: int) -> dict:
    start = time.perf_counter()
    panel = hj.explore(scene)
    built = time.perf_counter() - start

    def move(i: int) -> float:
        name, values = SHADING_MOVES[i % len(SHADING_MOVES)]
        return timed(lambda: setattr(panel.sliders[name], "value", values[(i // len(SHADING_MOVES)) % 2]))

    for i in range(2):  # warm-up
        move(i)
    shading_moves = [move(i) for i in range(2, 2 + moves)]

    geometry = hj.geometry_stage(scene)  # cached: the panel ran it on this very scene
    params = panel.params()
    stage = [
        timed(lambda: np.asarray(jax.block_until_ready(hj.shading_stage(geometry, params))))
        for _ in range(moves)
    ]
    rgb = np.asarray(hj.shading_stage(geometry, params))[..., :3]
    with tempfile.TemporaryDirectory() as folder:
        png = [
            timed(lambda: Path(hj.write_image(Path(folder) / "x.png", rgb)).read_bytes())
            for _ in range(moves)
        ]

    azimuth = panel.sliders["light_azimuth"]
    light = [timed(lambda: setattr(azimuth, "value", LIGHT_AZIMUTHS[i % 2])) for i in range(1 + light_moves)][
        1:
    ]
    return {
        "panel built": built,
        "shading move": statistics.median(shading_moves),
        "  shading stage": statistics.median(stage),
        "  PNG": statistics.median(png),
        "light move": statistics.median(light),
        "moves": {"shading": shading_moves, "light": light},
        "geometry_runs": panel.geometry_runs,
        "shading_runs": panel.shading_runs,
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=256, help="image width and height (pixels)")
    parser.add_argument("--moves", type=int, default=20, help="shading-slider moves timed")
    parser.add_argument("--light-moves", type=int, default=5, help="light-slider moves timed")
    parser.add_argument("--quick", action="store_true", help="tiny scene, few moves (test suite)")
    parser.add_argument("--json", type=Path, help="also write the figures here")
    args = parser.parse_args(argv)
    if args.quick:
        args.size, args.moves, args.light_moves = 48, 3, 1
    scene = bench_scene(args.size, args.quick)
    result = measure(scene, args.moves, args.light_moves)
    print(
        f"hairjax.explore latency: {platform.platform()}, {os.cpu_count()} CPUs, "
        f"jax {jax.__version__} ({jax.default_backend()})"
    )
    print(
        f"scene: default ({scene.strands.num_strands} strands) at {args.size}x{args.size}; medians of "
        f"{args.moves} shading and {args.light_moves} light moves"
    )
    for key in ("panel built", "shading move", "  shading stage", "  PNG", "light move"):
        print(f"{key:<18}{result[key] * 1e3:10.1f} ms")
    print(f"geometry stage runs: {result['geometry_runs']}, shading runs: {result['shading_runs']}")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"size": args.size, **result}, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
