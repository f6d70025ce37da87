"""`hairjax compare`: the JAX and GL renderers on one scene, pixel by pixel (docs/model.md)."""

from __future__ import annotations

import argparse

from ._outputs import Output, check_outputs, written_together

__all__ = ["run"]


def run(args: argparse.Namespace) -> int:
    from .._io._files import write_json
    from .._progress import reporter
    from ..tools import compare, format_report
    from ._scenes import load_cli_scene

    if args.json is not None:
        check_outputs([Output(args.json, (".json",), "--json")])
    scene = load_cli_scene(args, args.scene)
    with reporter("compare", quiet=args.quiet) as progress:
        report = compare(scene, repeats=args.repeats, progress=progress)
    print(format_report(report))
    if args.json is not None:
        with written_together([args.json]) as (tmp,):
            write_json(tmp, report)
        if not args.quiet:
            print(f"wrote {args.json}")
    return 0
