"""Reusing a visibility order while the view turns (kim-2003 §3, Fig. 8).

kim-2003 separates the visibility ordering from the drawing pass: "the viewpoint does not
change much from frame to frame", so the bin-sorted order can be computed periodically and
reused; their Fig. 8 draws a head turned by 30° with the order of the unturned view, and the
difference image "shows that there's some discrepancy against the correct order".

Here the draw order is computed once for the scene's camera (0°); the camera then turns
about the vertical axis through its target by each angle, and the scene is rendered (a)
with the stale 0° order (`hj.render(scene, order=…)`) and (b) with the order sorted for
that view, as usual. The light stays put, so the shadows are the same in (a) and (b) and
only the draw order differs. Per angle: RMSE and max |a − b| over the RGB channels (alpha
does not depend on the order), and the fraction of pixels where some channel differs by
more than 1/255. With `--gl` (on by default when OpenGL is available) the GL renderer
(`render_gl(scene, order=…)`) is measured the same way.

Timings: the order itself (`visibility_order`: projection, near-plane test and bin sort;
and the bin sort alone) against a full render from scratch (set-up, geometry and shading
stages: `forget` then `render`), medians of `--repeats` runs after a warm-up.

    python experiments/06_order_reuse.py                  # default scene + TressFX, 0–45°
    python experiments/06_order_reuse.py --quick          # tiny, for the test suite

Writes DIR/order_reuse.csv (scene, path, angle, rmse, max_abs, frac_visible),
DIR/order_reuse_timings.csv and DIR/order_reuse.png, and prints both tables.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCENES = {
    "default": lambda: _hj().load_scene(_hj().default_scene_path()),
    "tressfx": lambda: _hj().load_scene(ROOT / "experiments" / "scenes" / "tressfx_ponytail.toml"),
}
CSV_COLUMNS = ("scene", "path", "angle", "rmse", "max_abs", "frac_visible")
TIMING_COLUMNS = ("scene", "segments", "order_s", "sort_s", "render_jax_s", "render_gl_s")
VISIBLE = 1.0 / 255.0  # an 8-bit display step


def _hj():
    import hairjax

    return hairjax


def quick_scene():
    hj = _hj()
    return hj.Scene(
        hj.furball(200, 8, seed=2),
        camera=hj.Camera(eye=(0.0, 0.3, 3.5), width=40, height=40),
        shadows=hj.Shadows("none"),
        name="quick",
    )


def turned(scene, degrees: float):
    """`scene` with its camera turned by `degrees` about the vertical (world y) axis through
    the camera's target; `up` is world y's and stays."""
    cam = scene.camera
    a = np.radians(degrees)
    rot = np.array([[np.cos(a), 0.0, np.sin(a)], [0.0, 1.0, 0.0], [-np.sin(a), 0.0, np.cos(a)]])
    target = np.asarray(cam.target)
    eye = target + rot @ (np.asarray(cam.eye) - target)
    return scene.replace(camera=dataclasses.replace(cam, eye=tuple(float(x) for x in eye)))


def image_difference(a: np.ndarray, b: np.ndarray) -> dict:
    from hairjax.tools import image_stats

    a, b = np.asarray(a, np.float64)[..., :3], np.asarray(b, np.float64)[..., :3]
    stats = image_stats(a, b)
    return dict(
        rmse=stats["rmse"],
        max_abs=stats["max_abs"],
        frac_visible=float(np.mean(np.abs(a - b).max(axis=-1) > VISIBLE)),
    )


def _timings(name, scene, repeats: int, gl: bool) -> dict:
    import jax

    from hairjax import render
    from hairjax.experimental import draw_order, forget, segment_depth, visibility_order
    from hairjax.tools import median_time

    _, _, depth, segments, order = visibility_order(scene)
    seg = segments[order]  # every drawable segment

    def full_render():
        forget(scene)
        jax.block_until_ready(render(scene))

    row = dict(
        scene=name,
        segments=len(order),
        order_s=median_time(lambda: visibility_order(scene), repeats),
        sort_s=median_time(lambda: draw_order(segment_depth(depth, seg), scene.ordering), repeats),
        render_jax_s=median_time(full_render, repeats),
        render_gl_s=float("nan"),
    )
    if gl:
        from hairjax.gl import render_gl

        row["render_gl_s"] = median_time(lambda: render_gl(scene), repeats)
    return row


def _gl_available() -> bool:
    try:
        from hairjax.gl import get_context

        get_context()
        return True
    except Exception:  # noqa: BLE001 — GLUnavailable, or moderngl missing altogether
        return False


def _plot(rows, path: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    styles = {"jax": dict(marker="o", linestyle="-"), "gl": dict(marker="x", linestyle="--")}
    for scene, path_name in sorted({(r["scene"], r["path"]) for r in rows}):
        sel = sorted(
            (r for r in rows if (r["scene"], r["path"]) == (scene, path_name)), key=lambda r: r["angle"]
        )
        angles = [r["angle"] for r in sel]
        color = f"C{scenes.index(scene)}"
        for ax, key in zip(axes, ("rmse", "max_abs")):
            ax.plot(
                angles,
                [r[key] for r in sel],
                color=color,
                label=f"{scene} ({path_name})",
                **styles.get(path_name, {}),
            )
    for ax, label in zip(axes, ("RMSE, stale vs fresh order", "max |stale − fresh|")):
        ax.set_xlabel("camera turned by (degrees)")
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _fmt_s(s: float) -> str:
    return "–" if not np.isfinite(s) else (f"{s * 1e3:.1f} ms" if s < 1 else f"{s:.2f} s")


def _parse_angles(text: str) -> list[float]:
    try:
        angles = [float(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"--angles takes numbers separated by commas: {text!r}")
    if not angles:
        raise argparse.ArgumentTypeError("--angles needs at least one angle")
    return sorted(set(angles) | {0.0})


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scenes", default="default,tressfx", help=f"among {', '.join(SCENES)}")
    p.add_argument(
        "--angles",
        type=_parse_angles,
        default=[float(a) for a in range(0, 50, 5)],
        help="degrees, comma-separated (default 0,5,...,45; 0 is always added)",
    )
    p.add_argument("--repeats", type=int, default=3, help="timing runs, median (default 3)")
    p.add_argument(
        "--gl",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="also measure the GL renderer (default: when OpenGL is available)",
    )
    p.add_argument("--out", type=Path, default=Path("out/order_reuse"))
    p.add_argument(
        "--quick",
        action="store_true",
        help="a 200-strand ball at 40² without shadows, angles 0,10,30, JAX only, 1 timing run",
    )
    return p


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    if args.repeats < 1:
        raise SystemExit("--repeats must be at least 1")
    hj = _hj()
    from hairjax.experimental import visibility_order

    if args.quick:
        scenes = {"quick": quick_scene}
        args.angles, args.repeats = [0.0, 10.0, 30.0], 1
        args.gl = False if args.gl is None else args.gl
    else:
        unknown = [s for s in args.scenes.split(",") if s not in SCENES]
        if unknown:
            raise SystemExit(f"unknown scene(s) {', '.join(unknown)}; choose from {', '.join(SCENES)}")
        scenes = {k: SCENES[k] for k in args.scenes.split(",")}
    gl = _gl_available() if args.gl is None else args.gl
    render_gl = None
    if gl:
        from hairjax.gl import render_gl

    rows, timing_rows, titles = [], [], []
    started = time.perf_counter()
    for name, make in scenes.items():
        scene = make()
        cam = scene.camera
        titles.append(f"{name}: {scene.strands.num_strands:,} strands, {cam.width}×{cam.height}")
        print(
            f"scene {titles[-1]}; ordering {scene.ordering.method} ({scene.ordering.bins} bins)", flush=True
        )
        stale = visibility_order(scene)[4]  # the 0° order, reused at every angle
        for angle in args.angles:
            view = turned(scene, angle)
            # Both renders run the set-up afresh: `view` is a new scene object (its cache is
            # empty) and a given order is never cached.
            fresh = np.asarray(hj.render(view))
            reused = np.asarray(hj.render(view, order=stale))
            rows.append(dict(scene=name, path="jax", angle=angle, **image_difference(reused, fresh)))
            if gl:
                d = image_difference(render_gl(view, order=stale).image, render_gl(view).image)
                rows.append(dict(scene=name, path="gl", angle=angle, **d))
            print(
                f"  {angle:5.1f}°  "
                + "  ".join(
                    f"{r['path']}: rmse {r['rmse']:.2e} max {r['max_abs']:.2e} "
                    f"visible {100 * r['frac_visible']:.2f} %"
                    for r in rows
                    if r["scene"] == name and r["angle"] == angle
                )
                + f"  ({time.perf_counter() - started:.0f} s)",
                flush=True,
            )
            del view
        timing_rows.append(_timings(name, scene, args.repeats, gl))

    csv_path = args.out / "order_reuse.csv"
    timings_path = args.out / "order_reuse_timings.csv"
    png_path = args.out / "order_reuse.png"
    from hairjax.experimental import write_csv

    write_csv(csv_path, CSV_COLUMNS, rows, float_format=".6g")
    write_csv(timings_path, TIMING_COLUMNS, timing_rows, float_format=".6g")
    _plot(rows, png_path, "Stale (0°) vs fresh visibility order — " + "; ".join(titles))

    print()
    print(f"{'scene':<10} {'path':<4} {'angle':>6} {'RMSE':>10} {'max abs':>10} {'> 1/255':>9}")
    for r in rows:
        print(
            f"{r['scene']:<10} {r['path']:<4} {r['angle']:6.1f} {r['rmse']:10.3e} "
            f"{r['max_abs']:10.3e} {100 * r['frac_visible']:8.2f}%"
        )
    print()
    print(f"median of {args.repeats} run(s) after a warm-up")
    print(
        f"{'scene':<10} {'segments':>9} {'order':>10} {'bin sort':>10} {'JAX render':>11} "
        f"{'GL render':>10} {'order/JAX':>9} {'order/GL':>9}"
    )
    for t in timing_rows:
        print(
            f"{t['scene']:<10} {t['segments']:>9,} {_fmt_s(t['order_s']):>10} {_fmt_s(t['sort_s']):>10} "
            f"{_fmt_s(t['render_jax_s']):>11} {_fmt_s(t['render_gl_s']):>10} "
            f"{100 * t['order_s'] / t['render_jax_s']:8.2f}% {100 * t['order_s'] / t['render_gl_s']:8.2f}%"
        )
    print(f"\nwrote {csv_path}\nwrote {timings_path}\nwrote {png_path}")
    print(f"total {time.perf_counter() - started:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
