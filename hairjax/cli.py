"""The `hairjax` command line: render, animate, compare, fit, sweep, info, bench."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

__all__ = ["main"]


def _render(args) -> int:
    import numpy as np

    from ._io._image import write_image
    from ._render import render, render_profiled
    from ._scene._file import default_scene_path, load_scene

    scene = load_scene(args.scene or default_scene_path())
    if args.backend == "gl":
        from .gl import render_gl

        result = render_gl(scene)
        if args.profile:
            warm = render_gl(scene).timings  # the second run: shaders built
            for key in result.timings:
                print(f"{key:<14} {result.timings[key]:8.3f} s  {warm[key]:8.3f} s")
        image = result.image
    elif args.profile:
        image, timings = render_profiled(scene)
        # A second run shows the steady state, with compilation out of the way.
        _, warm = render_profiled(scene)
        width = max(len(k) for k in timings)
        print(f"{'stage':<{width}}  first run  second run")
        for key in timings:
            print(f"{key:<{width}}  {timings[key]:8.3f} s  {warm[key]:8.3f} s")
    else:
        image = np.asarray(render(scene))
    image = np.asarray(image)
    if not np.all(np.isfinite(image)):
        print("hairjax: warning: the image has non-finite pixels", file=sys.stderr)
    write_image(args.output, image)
    print(f"wrote {args.output}")
    if args.png:
        write_image(args.png, image)
        print(f"wrote {args.png}")
    return 0


def _animate(args) -> int:
    from ._animate import load_animation, write_frames

    animation = load_animation(args.scene)
    written = write_frames(
        animation,
        args.output,
        frames=args.frames,
        backend=args.backend,
        png=args.png,
        gif=args.gif,
        progress=sys.stderr.isatty(),
    )
    frames = sum(p.suffix == ".exr" for p in written)
    print(f"wrote {frames} frames ({', '.join(sorted({p.suffix for p in written}))}) to {args.output}")
    return 0


def _compare(args) -> int:
    from ._io._files import write_json
    from ._scene._file import default_scene_path, load_scene
    from .tools import compare, format_report

    report = compare(load_scene(args.scene or default_scene_path()), repeats=args.repeats)
    print(format_report(report))
    if args.json:
        print(f"wrote {write_json(args.json, report)}")
    return 0


def _fit(args) -> int:
    import numpy as np

    from ._fit import FitError, fit
    from ._io._files import write_json
    from ._io._image import read_image, write_image
    from ._render import render
    from ._scene._file import default_scene_path, load_scene

    if len(args.scenes) >= len(args.target):
        raise FitError(
            f"{1 + len(args.scenes)} scenes for {len(args.target)} targets: "
            "each extra --scene goes with one extra --target"
        )
    # Everything is read and checked before any rendering starts.
    targets = [read_image(t) for t in args.target]
    first = load_scene(args.scene or default_scene_path())
    extra = [load_scene(s) for s in args.scenes]
    scenes = [first, *extra, *[first] * (len(targets) - 1 - len(extra))]
    # Each shading model has its parameters (docs/model.md §17 for Scheuermann's).
    fittable = first.shading.fittable
    names = fittable if args.fit is None else tuple(n.strip() for n in args.fit.split(",") if n.strip())
    unknown = [n for n in names if n not in fittable]
    if unknown:
        raise FitError(f"unknown parameter {unknown[0]!r} in --fit; fittable: {', '.join(fittable)}")

    def progress(step, loss, elapsed):
        print(f"  step {step:4d}   loss {loss:.6e}   {elapsed:7.2f} s", file=sys.stderr, flush=True)

    print(f"fitting {', '.join(names)} with {args.solver} to {len(targets)} target(s)", file=sys.stderr)
    result = fit(scenes, targets, fit=names, solver=args.solver, max_steps=args.max_steps, progress=progress)
    rows = []
    for name in fittable:
        fmt = lambda v: " ".join(f"{x:.6g}" for x in np.atleast_1d(np.asarray(v, float)))  # noqa: E731
        se = result.std_error.get(name)
        se_text = "undetermined" if name in result.undetermined else "fixed" if name not in names else fmt(se)
        rows.append((name, fmt(getattr(result.initial, name)), fmt(getattr(result.params, name)), se_text))
    widths = [
        max(len(r[i]) for r in rows + [("parameter", "initial", "fitted", "std. error")]) for i in range(4)
    ]
    for row in [("parameter", "initial", "fitted", "std. error"), *rows]:
        print("  ".join(c.ljust(w) for c, w in zip(row, widths)))
    restarted = f" ({result.restarts} restarts)" if result.restarts else ""
    print(
        f"{result.termination} after {result.steps} steps{restarted}, {result.time_s:.2f} s "
        f"(+ {result.geometry_s:.2f} s geometry); RMSE {result.rmse:.4g}"
    )
    if args.json:
        print(f"wrote {write_json(args.json, result.to_json())}")
    if args.out:
        write_image(args.out, np.asarray(render(first, result.params)))
        print(f"wrote {args.out}")
    return 0


def _sweep(args) -> int:
    import dataclasses

    from ._scene._file import default_scene_path, load_scene
    from .tools import KNOBS, PATHS, QUICK_KNOBS, SweepError, load_points, run_sweep, write_report

    table = QUICK_KNOBS if args.quick else KNOBS
    names = [k.strip() for k in args.knobs.split(",") if k.strip()] if args.knobs else list(table)
    unknown = [k for k in names if k not in KNOBS]
    if unknown:
        raise SweepError(f"unknown knob {unknown[0]!r}; knobs: {', '.join(KNOBS)}")
    paths = [p.strip() for p in args.paths.split(",") if p.strip()]
    if any(p not in PATHS for p in paths) or not paths:
        raise SweepError(f"--paths takes a comma list of {', '.join(PATHS)}, got {args.paths!r}")
    scene = load_scene(args.scene or default_scene_path())
    if args.size:
        scene = scene.replace(camera=dataclasses.replace(scene.camera, width=args.size, height=args.size))
    try:
        points = run_sweep(
            scene,
            args.out,
            knobs={k: table[k] for k in names},
            paths=paths,
            repeats=args.repeats,
            restart=args.restart,
            progress=sys.stderr.isatty(),
        )
    except KeyboardInterrupt:
        print(
            f"interrupted: {len(load_points(args.out))} points kept in {args.out}; "
            "run the same command again to resume",
            file=sys.stderr,
        )
        return 130
    import json

    config = json.loads((args.out / "sweep.json").read_text())
    files = write_report(args.out, points, config)
    print((args.out / "summary.md").read_text().split("## All points")[0].rstrip())
    for f in files.values():
        print(f"wrote {f}")
    return 0


def _info(args) -> int:
    from ._io import format_info, hair_info, load_hair

    strands = load_hair(args.file)
    print(format_info(args.file, hair_info(strands)))
    return 0


def _bench(args) -> int:
    from .tools import bench_main

    return bench_main(args)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="hairjax", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("render", help="render a scene (default: the built-in fur ball)")
    p.add_argument("scene", nargs="?", type=Path, help="scene TOML file (docs/scenes.md)")
    p.add_argument(
        "-o",
        "--output",
        type=Path,
        default=Path("out/render.exr"),
        help="output image, .exr (float) or .png (default: out/render.exr)",
    )
    p.add_argument("--png", type=Path, help="also write an 8-bit sRGB PNG here")
    p.add_argument("--profile", action="store_true", help="print the time of each stage")
    p.add_argument(
        "--backend",
        choices=["jax", "gl"],
        default="jax",
        help="jax: the differentiable reference; gl: the OpenGL renderer",
    )
    p.set_defaults(func=_render)

    p = sub.add_parser("animate", help="render the frames of an animated fur ball (wenzel-2002)")
    p.add_argument("scene", type=Path, help="scene TOML file with a fur ball and [animation]")
    p.add_argument("--frames", type=int, help="frames per loop (default: animation.frames)")
    p.add_argument(
        "-o",
        "--output",
        type=Path,
        default=Path("out/animation"),
        help="folder for frame_0000.exr, … (default: out/animation)",
    )
    p.add_argument(
        "--backend",
        choices=["jax", "gl"],
        default="jax",
        help="jax: the differentiable reference; gl: the OpenGL renderer",
    )
    p.add_argument("--png", action="store_true", help="also write frame_0000.png, … (8-bit sRGB)")
    p.add_argument("--gif", action="store_true", help="also write animation.gif (Pillow)")
    p.set_defaults(func=_animate)

    p = sub.add_parser("compare", help="render with JAX and GL and report the differences")
    p.add_argument("scene", nargs="?", type=Path, help="scene TOML file (default: built-in)")
    p.add_argument("--json", type=Path, help="also write the report as JSON")
    p.add_argument("--repeats", type=int, default=3, help="timed runs per renderer (median)")
    p.set_defaults(func=_compare)

    p = sub.add_parser("fit", help="fit Kd, Ks, shininess, kappa to target images")
    p.add_argument("scene", nargs="?", type=Path, help="scene of the first target (default: built-in)")
    p.add_argument(
        "--target",
        action="append",
        type=Path,
        required=True,
        help="target image (.exr linear, or .png sRGB); repeat for several",
    )
    p.add_argument(
        "--scene",
        dest="scenes",
        action="append",
        type=Path,
        default=[],
        help="scene of the next extra --target (default: the first scene)",
    )
    p.add_argument(
        "--fit",
        default=None,
        help="parameters to fit (default: kd,ks,shininess,kappa, or all of a Scheuermann scene's)",
    )
    p.add_argument("--solver", default="lm", help="lm, gauss-newton, dogleg or bfgs")
    p.add_argument("--max-steps", type=int, default=100)
    p.add_argument("--json", type=Path, help="write params, initial, steps, loss, … as JSON")
    p.add_argument("--out", type=Path, help="render the first scene with the fitted parameters")
    p.set_defaults(func=_fit)

    p = sub.add_parser("sweep", help="error against run time, one quality knob at a time")
    p.add_argument("scene", nargs="?", type=Path, help="scene TOML file (default: built-in)")
    p.add_argument(
        "--out",
        type=Path,
        default=Path("out/sweep"),
        help="folder for points.jsonl, sweep.csv, pareto.png, summary.md (resumable)",
    )
    p.add_argument(
        "--knobs", help="comma list among maps, map_resolution, bins, width, supersampling (default: all)"
    )
    p.add_argument("--paths", default="jax,gl", help="jax, gl or both (default)")
    p.add_argument("--repeats", type=int, default=3, help="timed renders per point (median)")
    p.add_argument("--size", type=int, help="render at SIZE × SIZE instead of the scene's size")
    p.add_argument("--quick", action="store_true", help="a few values per knob")
    p.add_argument("--restart", action="store_true", help="discard finished points in --out")
    p.set_defaults(func=_sweep)

    p = sub.add_parser("info", help="summarise a hair file (.hair, .tfx, .ply)")
    p.add_argument("file", type=Path)
    p.set_defaults(func=_info)

    p = sub.add_parser("bench", help="time the stages on fur balls (BENCHMARKS.md)")
    p.add_argument("--quick", action="store_true", help="small sizes only, for a smoke test")
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--json", type=Path, help="also write the figures as JSON")
    p.add_argument(
        "--backend",
        choices=["jax", "gl", "both"],
        default="jax",
        help="time the JAX path (default), the GL renderer, or both in the same "
        "process with the ratio of their full renders",
    )
    p.set_defaults(func=_bench)
    return parser


def _enable_compilation_cache() -> None:
    """Keep compiled XLA kernels on disk, so a second `hairjax` run skips compilation.

    The folder is $HAIRJAX_CACHE_DIR, else ~/.cache/hairjax/xla; set the variable to an
    empty string to turn the cache off.
    """
    import os

    import jax

    folder = os.environ.get("HAIRJAX_CACHE_DIR", str(Path.home() / ".cache" / "hairjax" / "xla"))
    if not folder or jax.config.jax_compilation_cache_dir:  # type: ignore[attr-defined]  # options are set at run time
        return  # off, or the user configured a cache already
    jax.config.update("jax_compilation_cache_dir", folder)
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.2)


def main(argv=None) -> int:
    from ._errors import HairFormatError, SceneError
    from ._io._image import ImageError
    from .gl import GLError, GLUnavailable

    args = build_parser().parse_args(argv)
    if args.command in ("render", "animate", "bench", "compare", "fit", "sweep"):
        _enable_compilation_cache()
    try:
        return args.func(args)
    except (SceneError, HairFormatError, ImageError, ValueError, GLUnavailable, GLError) as err:
        print(f"hairjax: error: {err}", file=sys.stderr)
        return 2
    except FileNotFoundError as err:
        print(f"hairjax: error: {err}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
