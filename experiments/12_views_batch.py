"""Batched views (`hairjax.render_views`) against one render per view: the shading stage's
time for V views of one scene, as one batched, sharded call and as V calls; and first the
time of each view's first render (its set-up, geometry and shading stages), which compiles
only where its fragments fall in a bucket no view before it had (docs/model.md §6).

    python experiments/12_views_batch.py            # default scene at 256², 4 views (~1 min)
    python experiments/12_views_batch.py --strands 2000 --size 64   # a smaller ball, quicker
    python experiments/12_views_batch.py --size 512 --spread 0.03   # views a degree apart

The views turn about the target by `--spread` radians in all. Prints medians of 5 runs
after a warm-up for the shading stage. Run with
XLA_FLAGS=--xla_force_host_platform_device_count=N to spread the views over N host devices.
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import jax
import numpy as np

import hairjax as hj
from hairjax.tools import median_time


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--size", type=int, default=256)
    p.add_argument("--views", type=int, default=4)
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--strands", type=int, help="the fur ball's strands (default: the scene's, 20,000)")
    p.add_argument("--spread", type=float, default=1.5, help="the views' turn about the target, radians")
    args = p.parse_args(argv)
    overrides = {"camera.width": args.size, "camera.height": args.size}
    if args.strands is not None:
        overrides["hair.strands"] = args.strands
    scene = hj.load_scene(hj.default_scene_path(), overrides)
    cam = scene.camera
    r = float(np.linalg.norm(np.subtract(cam.eye, cam.target)))
    cameras = [
        dataclasses.replace(cam, eye=(r * np.sin(a), cam.eye[1], r * np.cos(a)))
        for a in np.linspace(0.0, args.spread, args.views)
    ]
    scenes = hj.experimental.view_scenes(scene, cameras)
    firsts, geometries = [], []
    for s in scenes:  # each view's first render: its set-up, then cached
        t0 = time.perf_counter()
        geometries.append(hj.geometry_stage(s))
        jax.block_until_ready(hj.shading_stage(geometries[-1], scene.params))
        firsts.append(time.perf_counter() - t0)
    counts = [hj.experimental.prepare(s).frag_pixel.size for s in scenes]
    batch = hj.experimental.stack_geometries(geometries)
    params = scene.params
    one_by_one = median_time(lambda: [hj.shading_stage(g, params) for g in geometries], args.repeats)
    batched = median_time(lambda: hj.experimental.shade_views(batch, params), args.repeats)
    devices, strands = len(jax.devices()), scene.strands.num_strands
    print(f"{devices} device(s), {args.views} views of {args.size}², {strands} strands")
    print("first render of each view   : " + ", ".join(f"{t * 1e3:.0f} ms" for t in firsts))
    print(
        "  its fragments (bucket)    : "
        + ", ".join(f"{n:,} ({hj.experimental.fragment_bucket(n):,})" for n in counts)
    )
    print(f"shading, one call per view : {one_by_one * 1e3:8.1f} ms")
    print(f"shading, one batched call  : {batched * 1e3:8.1f} ms   ({one_by_one / batched:.2f}x)")
    return 0 if one_by_one > 0 and batched > 0 else 1


if __name__ == "__main__":
    raise SystemExit(main())
