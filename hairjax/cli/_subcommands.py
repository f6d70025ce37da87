"""Each subcommand's arguments: options, defaults and help lines, one function per
subcommand (`build_parser` in `_parser` adds them in COMMANDS' order). Standard library only."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from ._arguments import non_negative_float, positive_float, positive_int

if TYPE_CHECKING:
    import argparse

    from ._parser import Subcommands

__all__ = ["SOLVER_NAMES", "SUBCOMMAND_ARGUMENTS"]

# The fit's solvers and their short names, as `hairjax/_fit/_solvers.py` has them (a test
# keeps the two equal); listed here so that --help and the check need no optimistix.
SOLVER_NAMES = ("levenberg-marquardt", "lm", "gauss-newton", "gn", "dogleg", "bfgs")

_SCENE_HELP = "scene TOML file (docs/scenes.md), or a .hair/.tfx/.ply file framed automatically"
_BACKEND_HELP = "jax: the differentiable reference; gl: the OpenGL renderer"


def _render_arguments(commands: Subcommands) -> None:
    """`hairjax render`: the scene, the image files and the renderer."""
    p = commands.add("render", "render a scene (default: the built-in fur ball) to EXR and/or PNG")
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


def _reference_arguments(commands: Subcommands) -> None:
    """`hairjax reference`: the scene, the image files and the path tracer's samples."""
    p = commands.add(
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


def _view_arguments(commands: Subcommands) -> None:
    """`hairjax view`: the image, the PNG and the exposure."""
    p = commands.add("view", "tone-map an EXR to an 8-bit sRGB PNG", scene_options=False)
    p.add_argument("image", type=Path, help="image to view (.exr or .png)")
    p.add_argument("-o", "--output", type=Path, help="PNG to write (default: IMAGE with .png)")
    p.add_argument("--exposure", type=float, default=0.0, help="exposure in stops: pixels × 2**E")


def _animate_arguments(commands: Subcommands) -> None:
    """`hairjax animate`: the scene, the frames and their files."""
    p = commands.add("animate", "render the frames of an animated fur ball (wenzel-2002)")
    p.add_argument("scene", type=Path, help="scene TOML file with a fur ball and [animation]")
    p.add_argument("--frames", type=positive_int, help="frames per loop (default: animation.frames)")
    p.add_argument(
        "-o", "--output", type=Path, default=Path("out/animation"), help="folder for frame_0000.exr, …"
    )
    p.add_argument("--backend", choices=["jax", "gl"], default="jax", help=_BACKEND_HELP)
    p.add_argument("--png", action="store_true", help="also write frame_0000.png, … (8-bit sRGB)")
    p.add_argument("--gif", action="store_true", help="also write animation.gif")


def _compare_arguments(commands: Subcommands) -> None:
    """`hairjax compare`: the scene, the report's files and the timed runs."""
    p = commands.add("compare", "render with JAX and GL and report their differences, pixel by pixel")
    p.add_argument("scene", nargs="?", type=Path, help=_SCENE_HELP + " (default: the built-in fur ball)")
    p.add_argument("--json", type=Path, help="also write the report as JSON")
    p.add_argument(
        "--diff",
        type=Path,
        help="also write the difference: .png blue inside the explained band, orange-red outside it "
        "(README), .exr the signed GL − JAX",
    )
    p.add_argument("--repeats", type=positive_int, default=3, help="timed runs per renderer (their median)")


def _fit_arguments(commands: Subcommands) -> None:
    """`hairjax fit`: what it fits against, what it fits and how, and what it writes."""
    p = commands.add("fit", "fit the shading parameters (Kd, Ks, shininess, κ, …) to target images")
    p.add_argument("scene", nargs="?", type=Path, help="scene of the first --target (default: the built-in)")
    _fit_targets(p)
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
    _fit_outputs(p)


def _fit_targets(p: argparse.ArgumentParser) -> None:
    """The images a fit matches, their scenes and masks, and those it holds out."""
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


def _fit_outputs(p: argparse.ArgumentParser) -> None:
    """What a fit writes: its record, a render, a plot and a scene file."""
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


def _sweep_arguments(commands: Subcommands) -> None:
    """`hairjax sweep`: the scene, the folder, the knobs and the timed renders; then --joint's."""
    p = commands.add(
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
    _joint_arguments(p)


def _joint_arguments(p: argparse.ArgumentParser) -> None:
    """`hairjax sweep --joint`: the search of the knobs' combinations, and its bounds."""
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


def _info_arguments(commands: Subcommands) -> None:
    """`hairjax info`: the hair file."""
    p = commands.add("info", "summarise a hair file (.hair, .tfx, .ply)", scene_options=False)
    p.add_argument("file", type=Path, help="hair file")


def _bench_arguments(commands: Subcommands) -> None:
    """`hairjax bench`: sizes, runs, output and what it times."""
    p = commands.add(
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


# In COMMANDS' order: `hairjax --help` lists them so.
SUBCOMMAND_ARGUMENTS = (
    _render_arguments,
    _reference_arguments,
    _view_arguments,
    _animate_arguments,
    _compare_arguments,
    _fit_arguments,
    _sweep_arguments,
    _info_arguments,
    _bench_arguments,
)
