"""The `hairjax` command line: render, view, animate, compare, fit, sweep, info, bench.

`_parser` builds the parser from each subcommand's arguments (`_subcommands`) and their
types (`_arguments`), standard library only, so --help is instant; `_main`
runs one subcommand and turns failures into one line and an exit code, `_outputs`
checks every output before the work, `_scenes` reads a scene with --set/--seed/--size,
and each subcommand is one module, `_<command>.py`, with a `run(args) -> int`.
"""

from ._main import main as main

__all__ = ["main"]
