"""`hairjax sweep`: error against run time, one quality knob at a time, or (`--joint`) a
search of their combinations for the Pareto front (resumable)."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from ._main import EXIT_INTERRUPTED
from ._outputs import Output, check_outputs

if TYPE_CHECKING:
    from .._progress import Progress

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
    from ..tools import KNOBS, QUICK_KNOBS, run_sweep
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
    options = dict(knobs=knobs, paths=paths, repeats=args.repeats, restart=args.restart, target=target)
    return _search(args, out, lambda progress: run_sweep(scene, out, progress=progress, **options))


def _run_joint(args: argparse.Namespace) -> int:
    from ..tools import JOINT_KNOBS, QUICK_JOINT_KNOBS, SearchConfig, run_joint
    from ._scenes import load_cli_scene

    out = args.out or Path("out/joint")
    check_outputs([Output(out, (), "--out")])
    knobs = _knobs(args, QUICK_JOINT_KNOBS if args.quick else JOINT_KNOBS, JOINT_KNOBS)
    paths = _paths(args)
    stop_at = 5e-4 if args.stop_at is None else args.stop_at
    search = SearchConfig(stop_at=stop_at, budget=args.budget, budget_s=args.budget_s)
    scene = load_cli_scene(args, args.scene)
    options = dict(knobs=knobs, paths=paths, repeats=args.repeats, search=search, restart=args.restart)
    return _search(args, out, lambda progress: run_joint(scene, out, progress=progress, **options))


def _search(args: argparse.Namespace, out: Path, run: Callable[[Progress], list[dict]]) -> int:
    """`run(progress)` (`run_sweep` or `run_joint` into `out`), then its report: the
    summary printed up to its table, the files written named."""
    from .._progress import reporter
    from ..tools import write_report
    from ..tools._store import JOINT_STORE, SWEEP_STORE

    store = JOINT_STORE if args.joint else SWEEP_STORE
    try:
        with reporter(store.title, quiet=args.quiet) as progress:
            points = run(progress)
    except KeyboardInterrupt:
        return _interrupted(len(store.load(out)), out)
    config = json.loads((out / store.config).read_text())
    files = write_report(out, points, config)
    table = "## The fronts" if args.joint else "## All points"
    print(files["summary"].read_text().split(table)[0].rstrip())
    if not args.quiet:
        for f in files.values():
            print(f"wrote {f}")
    return 0
