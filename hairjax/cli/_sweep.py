"""`hairjax sweep`: error against run time, one quality knob at a time, or (`--joint`) a
search of their combinations for the Pareto front (resumable)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ._main import EXIT_INTERRUPTED
from ._outputs import Output, check_outputs

__all__ = ["run"]


def _knobs(args: argparse.Namespace, table: dict, known: dict) -> dict:
    from ..tools import SweepError

    names = [k.strip() for k in args.knobs.split(",") if k.strip()] if args.knobs else list(table)
    unknown = [k for k in names if k not in known]
    if unknown or not names:
        raise SweepError(f"unknown knob {unknown[0] if unknown else args.knobs!r}; knobs: {', '.join(known)}")
    return {k: table[k] for k in names}


def _paths(args: argparse.Namespace) -> list[str]:
    from ..tools import PATHS, SweepError

    paths = [p.strip() for p in args.paths.split(",") if p.strip()]
    if any(p not in PATHS for p in paths) or not paths:
        raise SweepError(f"--paths takes a comma list of {', '.join(PATHS)}, got {args.paths!r}")
    return paths


def _interrupted(count: int, out: Path) -> int:
    print(
        f"hairjax: interrupted: {count} points kept in {out}; run the same command again to resume",
        file=sys.stderr,
    )
    return EXIT_INTERRUPTED


def run(args: argparse.Namespace) -> int:
    from ..tools import SweepError

    if args.joint:
        if args.target is not None:
            raise SweepError(
                "--target is for the one-knob sweep; --joint measures against each renderer's "
                "converged reference"
            )
        return _run_joint(args)
    if args.stop_at is not None or args.budget is not None or args.budget_s is not None:
        raise SweepError("--stop-at, --budget and --budget-s are options of --joint")
    return _run_sweep(args)


def _run_sweep(args: argparse.Namespace) -> int:
    from .._progress import reporter
    from ..tools import KNOBS, QUICK_KNOBS, load_points, run_sweep, write_report
    from ._scenes import load_cli_scene

    out = args.out or Path("out/sweep")
    check_outputs([Output(out, (), "--out")])
    knobs = _knobs(args, QUICK_KNOBS if args.quick else KNOBS, KNOBS)
    paths = _paths(args)
    scene = load_cli_scene(args, args.scene)
    target = None
    if args.target is not None:
        from .._io._image import read_image

        target = read_image(args.target)
    try:
        with reporter("sweep", quiet=args.quiet) as progress:
            points = run_sweep(
                scene,
                out,
                knobs=knobs,
                paths=paths,
                repeats=args.repeats,
                restart=args.restart,
                progress=progress,
                target=target,
            )
    except KeyboardInterrupt:
        return _interrupted(len(load_points(out)), out)
    config = json.loads((out / "sweep.json").read_text())
    files = write_report(out, points, config)
    print((out / "summary.md").read_text().split("## All points")[0].rstrip())
    if not args.quiet:
        for f in files.values():
            print(f"wrote {f}")
    return 0


def _run_joint(args: argparse.Namespace) -> int:
    from .._progress import reporter
    from ..tools import (
        JOINT_KNOBS,
        QUICK_JOINT_KNOBS,
        SearchConfig,
        load_joint,
        run_joint,
        write_joint_report,
    )
    from ._scenes import load_cli_scene

    out = args.out or Path("out/joint")
    check_outputs([Output(out, (), "--out")])
    knobs = _knobs(args, QUICK_JOINT_KNOBS if args.quick else JOINT_KNOBS, JOINT_KNOBS)
    paths = _paths(args)
    stop_at = 5e-4 if args.stop_at is None else args.stop_at
    search = SearchConfig(stop_at=stop_at, budget=args.budget, budget_s=args.budget_s)
    scene = load_cli_scene(args, args.scene)
    try:
        with reporter("joint search", quiet=args.quiet) as progress:
            points = run_joint(
                scene,
                out,
                knobs=knobs,
                paths=paths,
                repeats=args.repeats,
                search=search,
                restart=args.restart,
                progress=progress,
            )
    except KeyboardInterrupt:
        return _interrupted(len(load_joint(out)), out)
    config = json.loads((out / "joint.json").read_text())
    files = write_joint_report(out, points, config)
    print((out / "joint.md").read_text().split("## The fronts")[0].rstrip())
    if not args.quiet:
        for f in files.values():
            print(f"wrote {f}")
    return 0
