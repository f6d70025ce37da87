"""`hairjax render`: a scene (or a bare hair file) to EXR and/or PNG, with a JSON sidecar."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from ._outputs import IMAGE_SUFFIXES, Output, check_outputs, written_together

__all__ = ["run"]

DEFAULT_OUTPUT = Path("out/render.exr")


def _render_jax(scene, progress):
    """The staged JAX render, a progress step per stage; returns (image, timings)."""
    import jax

    from .._geometry._setup import prepare
    from .._geometry._stage import geometry_stage
    from .._render import render
    from .._shading import shading_stage

    if scene.patches is not None:  # hair patches (docs/model.md §18) are one stage
        t0 = time.perf_counter()
        image = jax.block_until_ready(render(scene))
        progress(1, 1, "hair patches")
        return image, {"patches (four passes)": time.perf_counter() - t0}
    timings = {}
    t0 = time.perf_counter()
    progress(0, 3, "geometry set-up")
    prepare(scene)
    t1 = time.perf_counter()
    progress(1, 3, "geometry stage")
    geometry = jax.block_until_ready(geometry_stage(scene))
    t2 = time.perf_counter()
    progress(2, 3, "shading stage")
    image = jax.block_until_ready(shading_stage(geometry, scene.params))
    t3 = time.perf_counter()
    progress(3, 3, "done")
    timings["geometry set-up (NumPy)"] = t1 - t0
    timings["geometry opacity (JAX)"] = t2 - t1
    timings["shading"] = t3 - t2
    return image, timings


def _print_profile(first: dict, second: dict) -> None:
    first = {**first, "total": sum(first.values())}
    second = {**second, "total": sum(second.values())}
    width = max(len(k) for k in first)
    print(f"{'stage':<{width}}  first run  second run")
    for key in first:
        print(f"{key:<{width}}  {first[key]:8.3f} s  {second.get(key, float('nan')):8.3f} s")


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from .._progress import reporter
    from ._scenes import load_cli_scene, scene_overrides, scene_path

    images = [p for p in (args.output, args.png) if p is not None] or [DEFAULT_OUTPUT]
    outputs = [Output(p, IMAGE_SUFFIXES, "--png" if p == args.png else "-o") for p in images]
    check_outputs(outputs)  # first the images: the sidecar's name is the first image's
    sidecar = images[0].with_suffix(".json") if args.sidecar else None
    if sidecar is not None:
        check_outputs([*outputs, Output(sidecar, (".json",), "the sidecar (--no-sidecar: none)")])

    scene = load_cli_scene(args, args.scene)
    with reporter("render", quiet=args.quiet) as progress:
        if args.backend == "gl":
            from ..gl import render_gl

            result = render_gl(scene)
            progress(1, 1, "GL render")
            image, timings = np.asarray(result.image), dict(result.timings)
            if args.profile:
                _print_profile(timings, dict(render_gl(scene).timings))  # the second: shaders built
        else:
            image, timings = _render_jax(scene, progress)
            image = np.asarray(image)
            if args.profile:
                from .._cache import forget

                forget(scene)  # the second run repeats every stage, with compilation out of the way
                _print_profile(timings, _render_jax(scene, lambda *a: None)[1])
    if not np.all(np.isfinite(image)):
        print("hairjax: warning: the image has non-finite pixels", file=sys.stderr)

    from .._io._files import write_json
    from .._io._image import write_image
    from ._sidecar import render_record

    paths = images + ([sidecar] if sidecar is not None else [])
    with written_together(paths) as temps:
        for tmp in temps[: len(images)]:
            write_image(tmp, image)
        if sidecar is not None:
            path = scene_path(args.scene)
            record = render_record(scene, path, scene_overrides(args, path), args.backend, timings, images)
            write_json(temps[-1], record)
    if not args.quiet:
        for p in paths:
            print(f"wrote {p}")
    return 0
