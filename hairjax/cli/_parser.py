"""The command line's arguments: every subcommand, option, default and help line.

Standard library only, so `hairjax --help` answers before JAX is imported. Each
subcommand's work lives in its own module, `hairjax/cli/_<command>.py`, which `_main`
imports only once the arguments parse.
"""

from __future__ import annotations

import argparse
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

__all__ = [
    "build_parser",
    "parse_size",
    "positive_int",
    "parse_assignment",
    "parse_key",
    "SOLVER_NAMES",
    "COMMANDS",
]

# The fit's solvers and their short names, as `hairjax/_fit/_solvers.py` has them (a test
# keeps the two equal); listed here so that --help and the check need no optimistix.
SOLVER_NAMES = ("levenberg-marquardt", "lm", "gauss-newton", "gn", "dogleg", "bfgs")

COMMANDS = ("render", "reference", "view", "animate", "compare", "fit", "sweep", "info", "bench")


def positive_int(text: str) -> int:
    """argparse type: an integer ≥ 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return value


def non_negative_float(text: str) -> float:
    """argparse type: a finite number ≥ 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number ≥ 0, got {text!r}") from None
    if not 0 <= value < float("inf"):
        raise argparse.ArgumentTypeError(f"expected a number ≥ 0, got {text!r}")
    return value


def positive_float(text: str) -> float:
    """argparse type: a finite number > 0."""
    value = non_negative_float(text)
    if value == 0:
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}")
    return value


def parse_size(text: str) -> tuple[int, int | None]:
    """argparse type for --size: `W` (height follows the scene's aspect) or `WxH`."""
    width, sep, height = text.lower().partition("x")
    try:
        w = positive_int(width)
        h = positive_int(height) if sep else None
    except argparse.ArgumentTypeError:
        raise argparse.ArgumentTypeError(f"expected W or WxH in pixels, each ≥ 1, got {text!r}") from None
    return w, h


def parse_assignment(text: str) -> tuple[str, str]:
    """argparse type for --set: `table.key=value` (the value is read as TOML later)."""
    key, sep, value = text.partition("=")
    if not sep or not key.strip() or not value.strip():
        raise argparse.ArgumentTypeError(f"expected table.key=value, got {text!r}")
    return key.strip(), value.strip()


def parse_key(text: str) -> str:
    """argparse type for --unset: `table.key` (or a top-level key such as `name`)."""
    key = text.strip()
    if not key or "=" in key or any(not part for part in key.split(".")):
        raise argparse.ArgumentTypeError(f"expected table.key, got {text!r}")
    return key


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


_SCENE_HELP = "scene TOML file (docs/scenes.md), or a .hair/.tfx/.ply file framed automatically"
_BACKEND_HELP = "jax: the differentiable reference; gl: the OpenGL renderer"


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
    common, scene = _common(), _scene_options()

    def command(name, help, *, scene_options=True):
        parents = [common, scene] if scene_options else [common]
        return sub.add_parser(name, help=help, description=help, parents=parents, formatter_class=_Formatter)

    p = command("render", "render a scene (default: the built-in fur ball) to EXR and/or PNG")
    p.add_argument("scene", nargs="?", type=Path, help=_SCENE_HELP + " (default: the built-in fur ball)")
    p.add_argument(
        "-o",
        "--output",
        type=Path,
        help="output image, .exr (linear float) or .png (default: out/render.exr)",
    )
    p.add_argument(
        "--png", type=Path, help="also write an 8-bit sRGB PNG here, a .png file (alone: only the PNG)"
    )
    p.add_argument(
        "--profile", action="store_true", help="print the time of each stage, first and second run"
    )
    p.add_argument("--backend", choices=["jax", "gl"], default="jax", help=_BACKEND_HELP)
    p.add_argument(
        "--no-sidecar",
        dest="sidecar",
        action="store_false",
        help="do not write IMAGE.json (the scene as resolved, parameters, versions, timings)",
    )

    p = command(
        "reference",
        "render a scene's strands as physically based fibres with Mitsuba 3 (docs/reference.md)",
    )
    p.add_argument("scene", nargs="?", type=Path, help=_SCENE_HELP + " (default: the built-in fur ball)")
    p.add_argument(
        "-o",
        "--output",
        type=Path,
        help="output image, .exr (linear float, alpha = coverage) or .png (8-bit sRGB) "
        "(default: out/reference.exr)",
    )
    p.add_argument("--png", type=Path, help="also write an 8-bit sRGB PNG here (alone: only the PNG)")
    p.add_argument(
        "--no-sidecar",
        dest="sidecar",
        action="store_false",
        help="do not write IMAGE.json (the scene as resolved, melanin, spp, seed, versions, time)",
    )
    p.add_argument("--spp", type=positive_int, help="samples per pixel (default: reference.spp, 64)")
    p.add_argument(
        "--sample-seed",
        type=int,
        default=0,
        help="the path tracer's seed: the same seed and spp give the same image "
        "(--seed is the hair's, as for render)",
    )

    p = command("view", "tone-map an EXR to an 8-bit sRGB PNG", scene_options=False)
    p.add_argument("image", type=Path, help="image to view (.exr or .png)")
    p.add_argument("-o", "--output", type=Path, help="PNG to write (default: IMAGE with .png)")
    p.add_argument("--exposure", type=float, default=0.0, help="exposure in stops: pixels × 2**E")

    p = command("animate", "render the frames of an animated fur ball (wenzel-2002)")
    p.add_argument("scene", type=Path, help="scene TOML file with a fur ball and [animation]")
    p.add_argument("--frames", type=positive_int, help="frames per loop (default: animation.frames)")
    p.add_argument(
        "-o", "--output", type=Path, default=Path("out/animation"), help="folder for frame_0000.exr, …"
    )
    p.add_argument("--backend", choices=["jax", "gl"], default="jax", help=_BACKEND_HELP)
    p.add_argument("--png", action="store_true", help="also write frame_0000.png, … (8-bit sRGB)")
    p.add_argument("--gif", action="store_true", help="also write animation.gif")

    p = command("compare", "render with JAX and GL and report their differences, pixel by pixel")
    p.add_argument("scene", nargs="?", type=Path, help=_SCENE_HELP + " (default: the built-in fur ball)")
    p.add_argument("--json", type=Path, help="also write the report as JSON")
    p.add_argument(
        "--diff",
        type=Path,
        help="also write the difference: .png blue inside the explained band, orange-red outside it "
        "(README), .exr the signed GL − JAX",
    )
    p.add_argument("--repeats", type=positive_int, default=3, help="timed runs per renderer (their median)")

    p = command("fit", "fit the shading parameters (Kd, Ks, shininess, κ, …) to target images")
    p.add_argument("scene", nargs="?", type=Path, help="scene of the first --target (default: the built-in)")
    p.add_argument(
        "--target",
        action="append",
        type=Path,
        required=True,
        help="target image (.exr linear, or .png sRGB); repeat for several views",
    )
    p.add_argument(
        "--scene",
        dest="scenes",
        action="append",
        type=Path,
        default=[],
        help="scene of the 2nd, 3rd, … --target, in order; targets without one use the first scene",
    )
    p.add_argument(
        "--mask",
        dest="masks",
        action="append",
        type=Path,
        default=[],
        help="weights of the --target at the same position, 0 (left out) to 1: the image's alpha, "
        "or its first channel where it has none (docs/fitting.md, Target images and masks); "
        "targets without one count every pixel. Repeatable",
    )
    p.add_argument(
        "--holdout",
        action="append",
        type=Path,
        default=[],
        help="a target the fit does not see (another view or light); its RMSE is reported. Repeatable",
    )
    p.add_argument(
        "--holdout-scene",
        dest="holdout_scenes",
        action="append",
        type=Path,
        default=[],
        help="scene of each --holdout, in order; held-out targets without one use the first scene",
    )
    p.add_argument(
        "--fit",
        help="comma list of the parameters to fit "
        "(default: all the model's fittable ones, e.g. kd,ks,shininess,kappa; "
        "also light_direction, light_color: docs/fitting.md)",
    )
    p.add_argument(
        "--solver", default="lm", choices=SOLVER_NAMES, help="least-squares solver (lm, gn: short names)"
    )
    p.add_argument(
        "--max-steps", type=positive_int, default=100, help="solver steps before giving up (exit 3)"
    )
    p.add_argument(
        "--json", type=Path, help="write the fitted and initial parameters, steps, loss, … as JSON"
    )
    p.add_argument(
        "--out", type=Path, help="render the first scene with the fitted parameters (.exr or .png)"
    )
    p.add_argument(
        "--plot", type=Path, help="PNG of target, fit and residual side by side (the first target)"
    )
    p.add_argument(
        "--save-scene",
        type=Path,
        metavar="SCENE.toml",
        help="write the first scene with the fitted parameters as a scene file (docs/fitting.md)",
    )

    p = command(
        "sweep",
        "error against run time: one quality knob at a time, or (--joint) a search of their "
        "combinations for the Pareto front (resumable)",
    )
    p.add_argument("scene", nargs="?", type=Path, help=_SCENE_HELP + " (default: the built-in fur ball)")
    p.add_argument(
        "--out",
        type=Path,
        help="folder for points.jsonl, sweep.csv, pareto.png, summary.md (default: out/sweep); with "
        "--joint for joint.jsonl, pareto.csv, joint.csv, joint_pareto.png, joint.md (default: out/joint)",
    )
    p.add_argument(
        "--knobs",
        help="comma list among shadows, maps, map_resolution, layers, bins, width, supersampling "
        "(default: all)",
    )
    p.add_argument("--paths", default="jax,gl", help="renderers to time: jax, gl or both")
    p.add_argument("--repeats", type=positive_int, default=3, help="timed renders per point (their median)")
    p.add_argument("--quick", action="store_true", help="a few values per knob")
    p.add_argument("--restart", action="store_true", help="discard the finished points in --out")
    p.add_argument(
        "--target",
        type=Path,
        help="measure every point against this image (e.g. `hairjax reference`'s) instead of "
        "each renderer's converged reference (not with --joint)",
    )
    p.add_argument(
        "--joint",
        action="store_true",
        help="search combinations of the knobs for the cheapest settings at each error "
        "(docs/results.md, Joint search)",
    )
    p.add_argument(
        "--stop-at",
        type=non_negative_float,
        metavar="REL_RMSE",
        help="with --joint: the relative RMSE at which the search stops descending (default 0.0005)",
    )
    p.add_argument(
        "--budget",
        type=positive_int,
        metavar="N",
        help="with --joint: at most N points per renderer (default: no bound)",
    )
    p.add_argument(
        "--budget-s",
        type=positive_float,
        metavar="SECONDS",
        help="with --joint: at most this much measuring per renderer, e.g. 1800 (default: no bound)",
    )

    p = command("info", "summarise a hair file (.hair, .tfx, .ply)", scene_options=False)
    p.add_argument("file", type=Path, help="hair file")

    p = command(
        "bench",
        "time the stages, and each shading model's cost, on fur balls (BENCHMARKS.md)",
        scene_options=False,
    )
    p.add_argument("--quick", action="store_true", help="small sizes only, for a smoke test")
    p.add_argument("--repeats", type=positive_int, default=5, help="timed runs per case (their median)")
    p.add_argument("--json", type=Path, help="also write the figures as JSON")
    p.add_argument(
        "--backend",
        choices=["jax", "gl", "both"],
        default="jax",
        help="time the JAX path, the GL renderer, or both in one process with the ratio of their renders",
    )
    p.add_argument(
        "--models",
        metavar="NAMES",
        help="the cost-per-model table for these shading models only, comma-separated, e.g. "
        "kajiya-kay,marschner (default: every registered model)",
    )
    return parser
