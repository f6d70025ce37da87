"""GL render time against the number of opacity maps, with and without clipping.

Reproduces kim-2003 Fig. 16: the time of the opacity-map passes grows linearly with the
number of maps N when every segment is drawn into every map (the basic algorithm), and
sub-linearly when each segment is drawn only into the maps whose slice its depth range
meets (§4.2, `render_gl(scene, clip_slices=True)`). Both give the same image.

For each N the scene is rendered with `hairjax.gl.render_gl` `--repeats` times with each
setting (after one warm-up render that compiles the shaders); the figures are medians of
the wall time of the call ("total") and of its "shadows" timing (the opacity-map passes,
light frame included). A setting whose first run takes longer than `--single-run-above`
seconds is run once only (the output says so). The slope of log(time) against log(N) is
fitted over N >= 16 for both settings.

    python experiments/05_maps_vs_time.py [--scene PATH] [--repeats 3] [--out out/maps_vs_time]
        [--maps 1,2,4,...,512] [--single-run-above 60]

Writes DIR/maps_vs_time.csv and DIR/maps_vs_time.png, and prints a table.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from pathlib import Path

import numpy as np

DEFAULT_MAPS = (1, 2, 4, 8, 16, 32, 64, 128, 256, 512)
SLOPE_FROM = 16  # fit the slope over N >= this
SETTINGS = (("clipped", True), ("unclipped", False))
CSV_COLUMNS = (
    "maps",
    "clipped_s",
    "unclipped_s",
    "clipped_shadows_s",
    "unclipped_shadows_s",
    "clipped_runs",
    "unclipped_runs",
)


def _parse_maps(text: str) -> list[int]:
    try:
        maps = [int(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"--maps takes integers separated by commas: {text!r}")
    if not maps or any(n < 1 for n in maps):
        raise argparse.ArgumentTypeError(f"--maps takes positive integers: {text!r}")
    return sorted(set(maps))


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scene", type=Path, help="scene TOML (default: the built-in default scene)")
    p.add_argument("--repeats", type=int, default=3, help="runs per setting, median (default 3)")
    p.add_argument(
        "--out", type=Path, default=Path("out/maps_vs_time"), help="output folder (default out/maps_vs_time)"
    )
    p.add_argument(
        "--maps",
        type=_parse_maps,
        default=list(DEFAULT_MAPS),
        help="numbers of opacity maps, comma-separated (default 1,2,4,...,512)",
    )
    p.add_argument(
        "--single-run-above",
        type=float,
        default=60.0,
        metavar="SECONDS",
        help="run a setting once only if its first run takes longer (default 60)",
    )
    return p


def fit_slope(maps, seconds, start: int = SLOPE_FROM) -> float:
    """Least-squares slope of log(seconds) against log(maps) over maps >= start."""
    pts = [
        (math.log(n), math.log(t))
        for n, t in zip(maps, seconds)
        if n >= start and t is not None and t > 0 and math.isfinite(t)
    ]
    if len(pts) < 2:
        return float("nan")
    x, y = np.array(pts).T
    return float(np.polyfit(x, y, 1)[0])


def _time_setting(scene, clip: bool, repeats: int, single_run_above: float):
    from hairjax.gl import render_gl

    totals, shadows = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = render_gl(scene, clip_slices=clip)
        totals.append(time.perf_counter() - t0)
        shadows.append(float(result.timings.get("shadows", float("nan"))))
        del result
        if totals[0] > single_run_above:
            break
    return statistics.median(totals), statistics.median(shadows), len(totals)


def _fmt(s: float) -> str:
    return "-" if not math.isfinite(s) else (f"{s * 1e3:8.1f} ms" if s < 1 else f"{s:8.2f} s ")


def _plot(rows, slopes, path: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    maps = [r["maps"] for r in rows]
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    for name, color in (("unclipped", "tab:red"), ("clipped", "tab:blue")):
        label = "without clipping" if name == "unclipped" else "with clipping (§4.2)"
        slope = slopes[f"{name}_s"]
        ax.plot(
            maps,
            [r[f"{name}_s"] for r in rows],
            "o-",
            color=color,
            label=f"{label}, total (slope {slope:.2f})",
        )
        ax.plot(
            maps,
            [r[f"{name}_shadows_s"] for r in rows],
            "--",
            color=color,
            alpha=0.5,
            label=f"{label}, opacity-map passes",
        )
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xlabel("number of opacity maps N")
    ax.set_ylabel("GL render time (s)")
    ax.set_title(title, fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    if args.repeats < 1:
        raise SystemExit("--repeats must be at least 1")

    import hairjax
    from hairjax.gl import GLUnavailable, get_context, render_gl

    scene_path = args.scene or hairjax.default_scene_path()
    base = hairjax.load_scene(scene_path)
    if base.shadows.method != "opacity-maps":
        print(f"note: {scene_path} has shadows.method = {base.shadows.method!r}; timing opacity maps instead")
    try:
        ctx = get_context()
    except GLUnavailable as err:
        print(f"GL unavailable: {err}", file=sys.stderr)
        return 2

    res = base.shadows.resolution
    s = base.strands
    title = (
        f"{base.name}: {s.num_strands:,} strands, {base.camera.width}x{base.camera.height}, maps of {res}^2"
    )
    print(f"scene {scene_path} ({title})")
    print(f"GL: {ctx.info.get('GL_RENDERER')} ({ctx.info.get('GL_VERSION')})")
    print(
        f"median of {args.repeats} run(s) per setting after 1 warm-up; a setting whose first "
        f"run exceeds {args.single_run_above:g} s is run once"
    )

    def with_maps(n):
        return base.replace(
            shadows=hairjax.Shadows("opacity-maps", maps=n, resolution=base.shadows.resolution)
        )

    render_gl(with_maps(args.maps[0]))  # warm-up: shader compilation

    rows, single = [], []
    started = time.perf_counter()
    for n in args.maps:
        scene = with_maps(n)
        row = {"maps": n}
        for name, clip in SETTINGS:
            total, shadows, runs = _time_setting(scene, clip, args.repeats, args.single_run_above)
            row[f"{name}_s"], row[f"{name}_shadows_s"], row[f"{name}_runs"] = total, shadows, runs
            if runs < args.repeats:
                single.append(f"N={n} {name}")
        rows.append(row)
        print(
            f"  N={n:4d}: clipped {_fmt(row['clipped_s'])}  unclipped {_fmt(row['unclipped_s'])}"
            f"  ({time.perf_counter() - started:.0f} s so far)",
            flush=True,
        )

    maps = [r["maps"] for r in rows]
    slopes = {
        key: fit_slope(maps, [r[key] for r in rows])
        for key in ("clipped_s", "unclipped_s", "clipped_shadows_s", "unclipped_shadows_s")
    }

    args.out.mkdir(parents=True, exist_ok=True)
    from hairjax.experimental import write_csv

    csv_path = write_csv(args.out / "maps_vs_time.csv", CSV_COLUMNS, rows, float_format=".6f")
    png_path = args.out / "maps_vs_time.png"
    _plot(rows, slopes, png_path, title)

    print()
    print("    N   clipped total  clipped shadows   unclipped total  unclipped shadows  unclipped/clipped")
    for r in rows:
        ratio = r["unclipped_s"] / r["clipped_s"] if r["clipped_s"] > 0 else float("nan")
        mark = lambda name: "*" if r[f"{name}_runs"] < args.repeats else " "  # noqa: E731
        print(
            f"  {r['maps']:3d}     {_fmt(r['clipped_s'])}{mark('clipped')}     "
            f"{_fmt(r['clipped_shadows_s'])}      {_fmt(r['unclipped_s'])}{mark('unclipped')}"
            f"       {_fmt(r['unclipped_shadows_s'])}         {ratio:6.2f}x"
        )
    if single:
        print(f"* one run only (first run over {args.single_run_above:g} s): {', '.join(single)}")
    print()
    print(f"slope of log(time) vs log(N), N >= {SLOPE_FROM} (1 = linear):")
    for name in ("clipped", "unclipped"):
        print(
            f"  {name:9s}: total {slopes[f'{name}_s']:.2f}, "
            f"opacity-map passes {slopes[f'{name}_shadows_s']:.2f}"
        )
    print(f"\nwrote {csv_path}\nwrote {png_path}")
    print(f"total {time.perf_counter() - started:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
