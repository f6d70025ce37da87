"""The command line's arguments: help, defaults, option checks, --version."""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

import pytest
from helpers import REPO

from hairjax.cli import main
from hairjax.cli._parser import COMMANDS, SOLVER_NAMES, build_parser, parse_assignment, parse_size


def _subparsers(parser):
    (action,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return action.choices


def test_every_command_is_listed():
    assert set(_subparsers(build_parser())) == set(COMMANDS)


@pytest.mark.parametrize("command", COMMANDS)
def test_every_option_has_a_help_line_and_shows_its_default(command):
    sub = _subparsers(build_parser())[command]
    text = sub.format_help()
    for action in sub._actions:
        assert action.help, f"{command} {action.option_strings or action.dest} has no help"
        has_default = action.option_strings and action.default not in (
            None,
            False,
            True,
            [],
            argparse.SUPPRESS,
        )
        if has_default and not isinstance(action, argparse._HelpAction):
            shown = (
                "x".join(map(str, action.default))
                if isinstance(action.default, tuple)
                else str(action.default)
            )
            assert f"default: {shown}" in " ".join(text.split()), f"{command} {action.option_strings[0]}"


def test_solver_names_are_the_fits():
    from hairjax._fit._solvers import ALIASES, SOLVERS

    assert set(SOLVER_NAMES) == set(SOLVERS) | set(ALIASES)


def test_help_does_not_import_jax():
    """--help parses before anything heavy is imported (its time is in BENCHMARKS.md)."""
    code = (
        "import sys, json, contextlib, io\n"
        "from hairjax.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    try:\n        main(['render', '--help'])\n    except SystemExit:\n        pass\n"
        "print(json.dumps(sorted(m for m in sys.modules if m.split('.')[0] in ('jax', 'numpy', 'moderngl'))))"
    )
    env = dict(
        os.environ, PYTHONPATH=os.pathsep.join(p for p in (str(REPO), os.environ.get("PYTHONPATH")) if p)
    )
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    ).stdout
    assert json.loads(out.strip().splitlines()[-1]) == []


def test_version(capsys):
    import hairjax

    with pytest.raises(SystemExit) as info:
        main(["--version"])
    assert info.value.code == 0
    assert capsys.readouterr().out.strip() == f"hairjax {hairjax.__version__}"


@pytest.mark.parametrize(
    "argv, option",
    [
        (["fit", "--target", "t.exr", "--max-steps", "-1"], "--max-steps"),
        (["fit", "--target", "t.exr", "--solver", "newton"], "--solver"),
        (["compare", "--repeats", "0"], "--repeats"),
        (["sweep", "--size", "0"], "--size"),
        (["sweep", "--size", "-5"], "--size"),
        (["sweep", "--repeats", "0"], "--repeats"),
        (["sweep", "--joint", "--budget", "0"], "--budget"),
        (["sweep", "--joint", "--stop-at", "-0.1"], "--stop-at"),
        (["sweep", "--joint", "--stop-at", "nan"], "--stop-at"),
        (["sweep", "--joint", "--budget-s", "0"], "--budget-s"),
        (["render", "--size", "12x0"], "--size"),
        (["render", "--set", "camera.fov"], "--set"),
        (["animate", "s.toml", "--frames", "0"], "--frames"),
    ],
)
def test_bad_option_values_are_refused_before_anything_runs(argv, option, capsys):
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert f"argument {option}" in err and "Traceback" not in err


def test_parse_size():
    assert parse_size("256") == (256, None)
    assert parse_size("320x240") == (320, 240)
    assert parse_size("320X240") == (320, 240)
    for bad in ("0", "-5", "x", "12x", "axb", "1.5"):
        with pytest.raises(argparse.ArgumentTypeError):
            parse_size(bad)


def test_parse_assignment():
    assert parse_assignment("shading.kd = 0.3") == ("shading.kd", "0.3")
    assert parse_assignment("light.direction=[0, 1, 1]") == ("light.direction", "[0, 1, 1]")
    for bad in ("shading.kd", "=3", "shading.kd="):
        with pytest.raises(argparse.ArgumentTypeError):
            parse_assignment(bad)
