"""`hairjax bench`: time the stages on fur balls (the figures of BENCHMARKS.md)."""

from __future__ import annotations

import argparse

from ._outputs import Output, check_outputs

__all__ = ["run"]


def run(args: argparse.Namespace) -> int:
    from ..tools import bench_main

    if args.json is not None:
        check_outputs([Output(args.json, (".json",), "--json")])
    return bench_main(args)
