"""How much of a JAX render is spent mapping fresh memory: the page faults one render of the
bench scene takes, and what a fault costs on this machine (BENCHMARKS.md, "Fresh pages").

    python experiments/17_page_faults.py                                  # 20k, 512² (~1 min)
    python experiments/17_page_faults.py --strands 100000 --size 1024     # (~2 min)

Each render allocates its fragment arrays afresh (the raster's fields, the grouped fields,
the opacity stage's outputs) and frees them when the scene is forgotten; the C library
hands large blocks back to the system, so the next render's first write to every page is
a page fault. The GL renderer keeps its buffers between frames and pays none. This script
counts the minor faults of each render (`getrusage`), times the faulting of fresh
anonymous memory alone (one write per page of a new mapping, against a second pass over
the same pages), and prints their product beside the render's time. Medians of `--repeats`
runs after a warm-up.
"""

from __future__ import annotations

import argparse
import mmap
import resource
import statistics
import time

import numpy as np

import hairjax as hj
from hairjax.tools import bench_scene

PAGE = mmap.PAGESIZE


def fault_cost(size_bytes: int, repeats: int) -> tuple[float, float]:
    """Seconds per page to touch a fresh anonymous mapping of `size_bytes` (one write per
    page), and to write the same pages again once mapped: medians of `repeats`."""
    fresh, mapped = [], []
    for _ in range(repeats):
        region = mmap.mmap(-1, size_bytes, flags=mmap.MAP_PRIVATE | mmap.MAP_ANONYMOUS)
        pages = np.frombuffer(region, np.uint8)
        t0 = time.perf_counter()
        pages[::PAGE] = 1
        t1 = time.perf_counter()
        pages[::PAGE] = 2
        t2 = time.perf_counter()
        del pages
        region.close()
        n = size_bytes // PAGE
        fresh.append((t1 - t0) / n)
        mapped.append((t2 - t1) / n)
    return statistics.median(fresh), statistics.median(mapped)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--strands", type=int, default=20_000)
    p.add_argument("--size", type=int, default=512)
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--probe-mib", type=int, default=256, help="size of the fresh mapping timed per repeat")
    args = p.parse_args(argv)
    scene = bench_scene(dict(strands=args.strands, size=args.size, maps=64, map_resolution=256))

    totals, faults = [], []
    for run in range(args.repeats + 1):  # the first run compiles
        before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
        _, timings = hj.render_profiled(scene)  # forgets the scene's stages first
        after = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
        if run:
            totals.append(timings["total"])
            faults.append(after - before)
    fresh, mapped = fault_cost(args.probe_mib << 20, args.repeats)
    render, n = statistics.median(totals), statistics.median(faults)
    faulting = n * fresh
    print(f"{args.strands} strands at {args.size}², {PAGE}-byte pages")
    rows = {
        "JAX full render": f"{render * 1e3:9.0f} ms",
        "minor page faults per render": f"{n:9.0f}   ({n * PAGE / 2**30:.2f} GiB first written)",
        "a fault, fresh mapping": f"{fresh * 1e6:9.2f} us per page",
        "a write, page already mapped": f"{mapped * 1e6:9.2f} us per page",
        "faults x cost": f"{faulting * 1e3:9.0f} ms",
    }
    width = max(map(len, rows))
    for name, value in rows.items():
        print(f"  {name:<{width}}  {value}")
    print(f"  share of the render: {faulting / render:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
