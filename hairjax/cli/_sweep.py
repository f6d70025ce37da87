"""`hairjax sweep`: error against run time, one quality knob at a time (resumable)."""

from __future__ import annotations

import argparse
import json
import sys

from ._main import EXIT_INTERRUPTED
from ._outputs import Output, check_outputs

__all__ = ["run"]


def run(args: argparse.Namespace) -> int:
    from .._progress import reporter
    from ..tools import KNOBS, PATHS, QUICK_KNOBS, SweepError, load_points, run_sweep, write_report
    from ._scenes import load_cli_scene

    check_outputs([Output(args.out, (), "--out")])
    table = QUICK_KNOBS if args.quick else KNOBS
    names = [k.strip() for k in args.knobs.split(",") if k.strip()] if args.knobs else list(table)
    unknown = [k for k in names if k not in KNOBS]
    if unknown or not names:
        raise SweepError(f"unknown knob {unknown[0] if unknown else args.knobs!r}; knobs: {', '.join(KNOBS)}")
    paths = [p.strip() for p in args.paths.split(",") if p.strip()]
    if any(p not in PATHS for p in paths) or not paths:
        raise SweepError(f"--paths takes a comma list of {', '.join(PATHS)}, got {args.paths!r}")
    scene = load_cli_scene(args, args.scene)
    target = None
    if args.target is not None:
        from .._io._image import read_image

        target = read_image(args.target)
    try:
        with reporter("sweep", quiet=args.quiet) as progress:
            points = run_sweep(
                scene,
                args.out,
                knobs={k: table[k] for k in names},
                paths=paths,
                repeats=args.repeats,
                restart=args.restart,
                progress=progress,
                target=target,
            )
    except KeyboardInterrupt:
        print(
            f"hairjax: interrupted: {len(load_points(args.out))} points kept in {args.out}; "
            "run the same command again to resume",
            file=sys.stderr,
        )
        return EXIT_INTERRUPTED
    config = json.loads((args.out / "sweep.json").read_text())
    files = write_report(args.out, points, config)
    print((args.out / "summary.md").read_text().split("## All points")[0].rstrip())
    if not args.quiet:
        for f in files.values():
            print(f"wrote {f}")
    return 0
