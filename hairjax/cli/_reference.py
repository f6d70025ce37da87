"""`hairjax reference`: the scene's strands as fibres, path traced by Mitsuba 3 (docs/reference.md).

Mitsuba is an optional extra: without it the command says `pip install 'hairjax[reference]'`
in one line, after the outputs are checked and before the scene is read.
"""

from __future__ import annotations

import argparse
import sys
import time

from ._outputs import IMAGE_SUFFIXES, Output, check_outputs, written_together

__all__ = ["run"]


def run(args: argparse.Namespace) -> int:
    from .._io._image import write_image
    from .._reference import reference_image
    from .._reference._mitsuba_scene import sample_count
    from .._reference._render import check_sampling, settings_of
    from .._reference._support import check_supported, import_mitsuba
    from ._scenes import load_cli_scene

    check_outputs([Output(args.output, IMAGE_SUFFIXES, "-o")])
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
    with written_together([args.output]) as (tmp,):
        write_image(tmp, image)
    if not args.quiet:
        camera = scene.camera
        print(
            f"reference: {camera.width}x{camera.height}, {spp} spp, seed {args.sample_seed}, "
            f"max_depth {settings.max_depth}, {scene.strands.num_strands:,} strands; {seconds:.2f} s"
        )
        print(f"wrote {args.output}")
    return 0
