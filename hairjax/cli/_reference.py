"""`hairjax reference`: the scene's strands as fibres, path traced by Mitsuba 3 (docs/reference.md).

Mitsuba is an optional extra: without it the command says `pip install 'hairjax[reference]'`
in one line, after the outputs are checked and before the scene is read. Like `render`,
it writes an EXR and/or a PNG and a JSON sidecar beside the first image (`_sidecar.py`:
the scene as resolved, the pigments, spp, seed, versions and time), all together.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from ._outputs import IMAGE_SUFFIXES, Output, check_outputs

__all__ = ["run"]

DEFAULT_OUTPUT = Path("out/reference.exr")


def _outputs(args: argparse.Namespace) -> tuple[list[Path], Path | None]:
    """The images (-o, --png; out/reference.exr when neither) and the sidecar, checked."""
    outputs = [Output(args.output, IMAGE_SUFFIXES, "-o")] if args.output is not None else []
    if args.png is not None:
        outputs.append(Output(args.png, (".png",), "--png"))
    outputs = outputs or [Output(DEFAULT_OUTPUT, IMAGE_SUFFIXES, "-o")]
    images = [out.path for out in outputs]
    sidecar = images[0].with_suffix(".json") if args.sidecar else None
    if sidecar is not None:
        outputs.append(Output(sidecar, (".json",), "the sidecar (--no-sidecar: none)"))
    check_outputs(outputs)
    return images, sidecar


def run(args: argparse.Namespace) -> int:
    from .._reference import reference_image
    from .._reference._mitsuba_scene import sample_count
    from .._reference._render import check_sampling, settings_of
    from .._reference._support import check_supported, import_mitsuba
    from ._scenes import load_cli_scene, recorded_changes, scene_path
    from ._sidecar import reference_record, write_image_and_record

    images, sidecar = _outputs(args)
    check_sampling(1 if args.spp is None else args.spp, args.sample_seed)  # before any work
    import_mitsuba()  # a missing extra is said before the (slow) hair is read
    scene = load_cli_scene(args, args.scene)
    check_supported(scene)
    settings = settings_of(scene)
    spp = sample_count(settings.spp if args.spp is None else args.spp)  # what the sampler takes
    if scene.strands.width_units == "pixels" and not args.quiet:
        print(
            "hairjax: note: hair.width is in pixels: each fibre is w·D/f world units thick at "
            "depth D, as wide on screen as its ribbon (docs/reference.md)",
            file=sys.stderr,
        )
    start = time.perf_counter()
    image = reference_image(scene, spp=spp, seed=args.sample_seed)
    seconds = time.perf_counter() - start

    def record():
        path = scene_path(args.scene)
        sampling = {"spp": spp, "sample_seed": args.sample_seed}
        return reference_record(scene, path, recorded_changes(args, path), sampling, seconds, images)

    paths = write_image_and_record(image, images, sidecar, record)
    if not args.quiet:
        camera = scene.camera
        print(
            f"reference: {camera.width}x{camera.height}, {spp} spp, seed {args.sample_seed}, "
            f"max_depth {settings.max_depth}, {scene.strands.num_strands:,} strands; {seconds:.2f} s"
        )
        for p in paths:
            print(f"wrote {p}")
    return 0
