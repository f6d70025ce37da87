"""The CPU floor of a device-resident geometry set-up: what XLA's sort and stream
compaction alone cost at the bench scene's fragment count, beside today's JAX render
(host set-up) and the GL renderer, in one process (BENCHMARKS.md, "The device-resident
set-up on this CPU").

    python experiments/13_device_floor.py                      # 20k strands, 512² (~2 min)
    python experiments/13_device_floor.py --strands 100000 --size 1024   # (~10 min)

A set-up that lives on the device must at least group the camera fragments by pixel in
draw order (a sort of F keys; the cheapest XLA form packs (pixel << 32 | index) into one
uint64 key and sorts keys alone) and keep the covered raster candidates (a compaction of
about 2.3 F candidates to F). Those two XLA primitives, plus today's opacity and shading
stages (already JAX), bound such a set-up's full render from below. Medians of
`--repeats` runs after a warm-up. "Today's render" is the host set-up's
(`placement="host"`, set here); experiment 19 times the set-up built on this floor.
"""

from __future__ import annotations

import argparse
import statistics
import time

import jax
import jax.numpy as jnp
import numpy as np

import hairjax as hj
from hairjax.tools import bench_scene

# Raster candidates per kept fragment in the bench scene (the rasteriser evaluates ~4 rows
# per column and keeps 1.8 of them: 12.4 M candidates for 5.5 M fragments at 20k / 512²).
CANDIDATES_PER_FRAGMENT = 2.25


def median_time(fn, repeats: int) -> float:
    jax.block_until_ready(fn())
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        jax.block_until_ready(fn())
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--strands", type=int, default=20_000)
    p.add_argument("--size", type=int, default=512)
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--no-gl", action="store_true", help="leave out the GL renderer")
    args = p.parse_args(argv)
    scene = bench_scene(dict(strands=args.strands, size=args.size, maps=64, map_resolution=256))

    rows = {}
    stages = []
    for _ in range(args.repeats + 1):  # the first run compiles
        _, timings = hj.render_profiled(scene, placement="host")  # the compiled loops, against XLA's
        stages.append(timings)
    stages = stages[1:]

    def stage(name):
        return statistics.median(t[name] for t in stages)

    rows["JAX render (host set-up)"] = stage("total")
    rows["  set-up (host)"] = stage("geometry set-up")
    for sub in ("rasterize", "sort fragments", "shadow set-up"):
        rows[f"    {sub} (host set-up)"] = stage(f"geometry/{sub}")
    rows["  geometry opacity + shading (JAX)"] = stage("geometry opacity (JAX)") + stage("shading")
    if not args.no_gl:
        from hairjax.gl import render_gl

        rows["GL render"] = median_time(lambda: render_gl(scene), args.repeats)

    pixel = np.asarray(hj.prepare(scene, placement="host").frag_pixel, np.uint32)
    n = pixel.size
    rng = np.random.default_rng(0)
    # The set-up's pixel keys in raster order (segment after segment): the sort's real input.
    raster_keys = pixel[rng.permutation(n)]
    with jax.enable_x64(True):  # uint64 keys need 64-bit types
        packed = jnp.asarray((raster_keys.astype(np.uint64) << np.uint64(32)) | np.arange(n, dtype=np.uint64))
        xla_sort = median_time(lambda: jnp.sort(packed), args.repeats)
    numpy_sort = median_time(lambda: np.argsort(raster_keys, kind="stable"), args.repeats)
    m = int(CANDIDATES_PER_FRAGMENT * n)
    mask_np = np.zeros(m, bool)
    mask_np[rng.choice(m, n, replace=False)] = True
    mask = jnp.asarray(mask_np)
    compact = jax.jit(lambda x: jnp.nonzero(x, size=n, fill_value=0)[0])
    xla_compact = median_time(lambda: compact(mask), args.repeats)
    numpy_compact = median_time(lambda: np.flatnonzero(mask_np), args.repeats)
    rows["sort F keys: XLA, packed uint64 keys only"] = xla_sort
    rows["sort F keys: NumPy, stable argsort"] = numpy_sort
    rows["compaction to F: XLA nonzero"] = xla_compact
    rows["compaction to F: NumPy flatnonzero"] = numpy_compact
    floor = xla_sort + xla_compact + rows["  geometry opacity + shading (JAX)"]
    rows["floor of a device set-up's render (XLA sort + compaction + stages)"] = floor

    counts = f"F = {n / 1e6:.1f} M camera fragments, {m / 1e6:.1f} M candidates"
    print(f"{args.strands} strands at {args.size}², {counts}")
    width = max(map(len, rows))
    for name, seconds in rows.items():
        print(f"  {name:<{width}}  {seconds * 1e3:9.0f} ms")
    if "GL render" in rows:
        print(f"  floor / GL render: {floor / rows['GL render']:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
