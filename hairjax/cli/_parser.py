"""The command line's parser: the top level, the options every subcommand shares and the
scene's; each subcommand's own arguments are in `_subcommands`, their types in `_arguments`.

Standard library only, so `hairjax --help` answers before JAX is imported. Each
subcommand's work lives in its own module, `hairjax/cli/_<command>.py`, which `_main`
imports only once the arguments parse.
"""

from __future__ import annotations

import argparse
import dataclasses
from importlib.metadata import PackageNotFoundError, version

from ._arguments import parse_assignment, parse_key
from ._arguments import parse_size as parse_size
from ._arguments import positive_int as positive_int
from ._subcommands import SOLVER_NAMES as SOLVER_NAMES
from ._subcommands import SUBCOMMAND_ARGUMENTS

__all__ = [
    "build_parser",
    "parse_size",
    "positive_int",
    "parse_assignment",
    "parse_key",
    "SOLVER_NAMES",
    "COMMANDS",
]

COMMANDS = ("render", "reference", "view", "animate", "compare", "fit", "sweep", "info", "bench")


class _Formatter(argparse.RawDescriptionHelpFormatter):
    """Help that shows each option's default, unless there is none or the help says it."""

    def _get_help_string(self, action):
        text = action.help or ""
        default = action.default
        if (
            "default" not in text
            and not isinstance(default, bool)
            and default not in (None, [], argparse.SUPPRESS)
            and action.option_strings
        ):
            shown = "x".join(str(d) for d in default) if isinstance(default, tuple) else default
            text += f" (default: {shown})"
        return text


def _version() -> str:
    try:
        return version("hairjax")
    except PackageNotFoundError:  # a source tree without installation
        return "0+unknown"


def _common() -> argparse.ArgumentParser:
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("-q", "--quiet", action="store_true", help="no progress and no 'wrote …' lines")
    common.add_argument("--debug", action="store_true", help="show the traceback of an unexpected error")
    return common


def _scene_options() -> argparse.ArgumentParser:
    scene = argparse.ArgumentParser(add_help=False)
    scene.add_argument(
        "--set",
        dest="overrides",
        action="append",
        type=parse_assignment,
        default=[],
        metavar="TABLE.KEY=VALUE",
        help="override a scene-file key, value in TOML (e.g. shading.kd=0.3, camera.fov=30); repeatable",
    )
    scene.add_argument(
        "--unset",
        action="append",
        type=parse_key,
        default=[],
        metavar="TABLE.KEY",
        help="remove a scene-file key, so its default applies (e.g. shadows.maps); repeatable",
    )
    scene.add_argument("--seed", type=int, help="random seed of procedural hair (hair.seed)")
    scene.add_argument(
        "--size",
        type=parse_size,
        metavar="W[xH]",
        help="image size in pixels; W alone keeps the scene's aspect ratio",
    )
    return scene


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="hairjax",
        description="Differentiable hair shading: render, compare, fit and measure (README.md).",
        epilog="exit codes: 0 done (a fit converged), 2 bad input, 3 a fit stopped without "
        "converging, 1 an unexpected error, 130 interrupted",
        formatter_class=_Formatter,
    )
    parser.add_argument("--version", action="version", version=f"hairjax {_version()}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    commands = Subcommands(sub, _common(), _scene_options())
    for add_arguments in SUBCOMMAND_ARGUMENTS:
        add_arguments(commands)
    return parser


@dataclasses.dataclass(frozen=True)
class Subcommands:
    """Adds the subcommands: each with --quiet and --debug (`common`), and the scene's
    options (`scene`) unless told otherwise."""

    sub: argparse._SubParsersAction[argparse.ArgumentParser]
    common: argparse.ArgumentParser
    scene: argparse.ArgumentParser

    def add(self, name: str, help: str, *, scene_options: bool = True) -> argparse.ArgumentParser:
        parents = [self.common, self.scene] if scene_options else [self.common]
        return self.sub.add_parser(
            name, help=help, description=help, parents=parents, formatter_class=_Formatter
        )
