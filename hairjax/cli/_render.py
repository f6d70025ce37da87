"""`hairjax render`: a scene (or a bare hair file) to EXR and/or PNG, with a JSON sidecar."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ._outputs import (
    FILE_OVERHEAD,
    IMAGE_SUFFIXES,
    Output,
    check_free_space,
    check_outputs,
    image_bytes,
)

__all__ = ["run"]

DEFAULT_OUTPUT = Path("out/render.exr")


def _with_total(timings: dict) -> dict:
    if "total" in timings:
        return dict(timings)
    return {**timings, "total": sum(timings.values())}  # the GL passes, one after another


def _print_profile(first: dict, second: dict) -> None:
    first, second = _with_total(first), _with_total(second)
    width = max(len(k) for k in first)
    print(f"{'stage':<{width}}  first run  second run")
    for key in first:
        print(f"{key:<{width}}  {first[key]:8.3f} s  {second.get(key, float('nan')):8.3f} s")


def _image_outputs(args: argparse.Namespace) -> list[Output]:
    """-o (EXR or PNG) and --png (PNG only), or the default -o."""
    outputs = []
    if args.output is not None or args.png is None:
        outputs.append(Output(args.output or DEFAULT_OUTPUT, IMAGE_SUFFIXES, "-o"))
    if args.png is not None:
        outputs.append(Output(args.png, (".png",), "--png"))
    return outputs


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from .._progress import reporter
    from ._scenes import load_cli_scene, recorded_changes, scene_path

    outputs = _image_outputs(args)
    check_outputs(outputs)  # first the images: the sidecar's name is the first image's
    images = [o.path for o in outputs]
    sidecar = images[0].with_suffix(".json") if args.sidecar else None
    if sidecar is not None:
        outputs = [*outputs, Output(sidecar, (".json",), "the sidecar (--no-sidecar: none)")]
        check_outputs(outputs)

    scene = load_cli_scene(args, args.scene)
    width, height = scene.camera.width, scene.camera.height
    check_free_space(
        [(o, FILE_OVERHEAD if o.path == sidecar else image_bytes(o.path, width, height)) for o in outputs]
    )
    with reporter("render", quiet=args.quiet) as progress:
        if args.backend == "gl":
            from ..gl import render_gl

            result = render_gl(scene)
            progress(1, 1, "GL render")
            image, timings = np.asarray(result.image), dict(result.timings)
            if args.profile:  # the second run, with the shaders built
                second = dict(render_gl(scene).timings)
        else:
            from .._render import render_profiled

            image, timings = render_profiled(scene, progress=progress)
            image = np.asarray(image)
            if args.profile:  # the second run repeats every stage, with compilation out of the way
                second = render_profiled(scene)[1]
    if args.profile:
        _print_profile(timings, second)
    if not np.all(np.isfinite(image)):
        print("hairjax: warning: the image has non-finite pixels", file=sys.stderr)

    from ._sidecar import render_record, write_image_and_record

    def record():
        path = scene_path(args.scene)
        return render_record(scene, path, recorded_changes(args, path), args.backend, timings, images)

    paths = write_image_and_record(image, images, sidecar, record)
    if not args.quiet:
        for p in paths:
            print(f"wrote {p}")
    return 0
