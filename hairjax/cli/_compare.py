"""`hairjax compare`: the JAX and GL renderers on one scene, pixel by pixel (docs/model.md),
with a verdict against the explained band and, with --diff, their difference image."""

from __future__ import annotations

import argparse

from ._outputs import IMAGE_SUFFIXES, Output, check_outputs, written_together

__all__ = ["run"]


def run(args: argparse.Namespace) -> int:
    from .._io._files import write_json
    from .._progress import reporter
    from ..tools import compare, format_report
    from ._scenes import load_cli_scene

    outputs = []
    if args.json is not None:
        outputs.append(Output(args.json, (".json",), "--json"))
    if args.diff is not None:
        outputs.append(Output(args.diff, IMAGE_SUFFIXES, "--diff"))
    check_outputs(outputs)
    scene = load_cli_scene(args, args.scene)
    with written_together([o.path for o in outputs]) as temps:
        paths = dict(zip((o.option for o in outputs), temps))
        with reporter("compare", quiet=args.quiet) as progress:
            report = compare(scene, repeats=args.repeats, progress=progress, diff=paths.get("--diff"))
        print(format_report(report))
        if args.json is not None:
            write_json(paths["--json"], report)
    if not args.quiet:
        for out in outputs:
            print(f"wrote {out.path}")
    return 0
