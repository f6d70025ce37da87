"""`hairjax animate`: the frames of wenzel-2002's moving fur ball (docs/model.md §14)."""

from __future__ import annotations

import argparse

from ._outputs import Output, check_outputs

__all__ = ["run"]


def run(args: argparse.Namespace) -> int:
    from .._animate import load_animation, write_frames
    from .._progress import reporter
    from ._scenes import options_blamed, scene_origins, scene_overrides

    check_outputs([Output(args.output, (), "-o")])
    with options_blamed(args.scene, scene_origins(args)):
        animation = load_animation(args.scene, scene_overrides(args, args.scene))
    with reporter("animate", quiet=args.quiet) as progress:
        written = write_frames(
            animation,
            args.output,
            frames=args.frames,
            backend=args.backend,
            png=args.png,
            gif=args.gif,
            progress=progress,
        )
    if not args.quiet:
        frames = sum(p.suffix == ".exr" for p in written)
        kinds = ", ".join(sorted({p.suffix for p in written}))
        print(f"wrote {frames} frames ({kinds}) to {args.output}")
    return 0
