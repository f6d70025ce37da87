"""`hairjax view`: tone-map an image (EXR, linear) to an 8-bit sRGB PNG to look at."""

from __future__ import annotations

import argparse

from ._outputs import BadOutput, Output, check_outputs, written_together

__all__ = ["run"]


def run(args: argparse.Namespace) -> int:
    from .._io._image import read_image, write_image

    output = args.output if args.output is not None else args.image.with_suffix(".png")
    if output.resolve() == args.image.resolve():
        raise BadOutput(f"{output}: is the input image; give another name with -o")
    check_outputs([Output(output, (".png",), "-o")])
    image = read_image(args.image)
    exposed = image.copy()
    exposed[..., :3] *= 2.0**args.exposure  # exposure in stops; alpha is not light
    with written_together([output]) as (tmp,):
        write_image(tmp, exposed)  # the PNG writer encodes linear RGB as 8-bit sRGB
    if not args.quiet:
        print(f"wrote {output}")
    return 0
