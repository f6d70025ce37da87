"""A static inside-to-outside order against per-view bin sorts: error against time.

scheuermann-2004 (slide 14) draws hair with a "static index buffer with inside to outside
draw order, computed at preprocess time", since back to front "for a head with hair is
very similar to inside to outside"; kim-2003 §3 sorts the segments into depth bins for
every view, and notes the order may be reused while the view changes little (Fig. 8).
Here (docs/model.md §4), while the camera turns about the vertical axis through its
target by each angle (0°…330° by default), each view is rendered with

- `static`: the inside-to-outside order, computed once from the geometry (`static_order`);
- `bins N`: the bin sort for this view, for several N;
- `bins N @0°`: the bin sort of the 0° view (the scene's N), reused at every angle;
- `none`: index order (the worst case, for scale);

and compared with the `exact` order of that view (`render(scene, order=…)`): RMSE and
max |a − exact| over the RGB channels and the share of pixels where some channel differs
by more than 1/255. The light stays put, so shadows are the same in every render and only
the draw order differs.

Timings, medians of `--repeats` runs after a warm-up: the computation that yields each
order from what the renderer has anyway (the projected depths): `draw_order` of the
segments' depths for `exact` and `bins N` — done for every view — and `static_order` for
`static` (the roots' centre and the distances) — done once; `bins N @0°` costs one bin
sort, once. The projection itself, common to all, is not included.

    python experiments/07_static_order.py       # default scene, TressFX, Scheuermann's head (192²)
    python experiments/07_static_order.py --quick       # tiny, for the test suite

Writes DIR/static_order.csv (scene, method, bins, angle, rmse, max_abs, frac_visible),
DIR/static_order_timings.csv (scene, method, bins, segments, when, order_s) and
DIR/static_order.png, and prints the tables.
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib.util
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
CSV_COLUMNS = ("scene", "method", "bins", "angle", "rmse", "max_abs", "frac_visible")
TIMING_COLUMNS = ("scene", "method", "bins", "segments", "when", "order_s")


def _sibling(name: str):
    """experiments/NAME.py (experiments/ is not a package)."""
    spec = importlib.util.spec_from_file_location(name, Path(__file__).with_name(f"{name}.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


_reuse = _sibling("06_order_reuse")
turned, image_difference, _angles = _reuse.turned, _reuse.image_difference, _reuse._parse_angles


def _hj():
    import hairjax

    return hairjax


def _sized(scene, size: int):
    cam = dataclasses.replace(scene.camera, width=size, height=size)
    return scene.replace(camera=cam)


SCENES = {
    "default": lambda size: _sized(_hj().load_scene(_hj().default_scene_path()), size),
    "tressfx": lambda size: _sized(
        _hj().load_scene(ROOT / "experiments" / "scenes" / "tressfx_ponytail.toml"), size
    ),
    # scheuermann-2004's case (slide 14): scalp hair on an opaque sphere head, which hides the far side.
    "head": lambda size: _sized(_hj().load_scene(ROOT / "experiments" / "scenes" / "scheuermann.toml"), size),
}


def quick_scene(size: int = 40):
    hj = _hj()
    return hj.Scene(
        hj.furball(200, 8, seed=2),
        camera=hj.Camera(eye=(0.0, 0.3, 3.5), width=size, height=size),
        shadows=hj.Shadows("none"),
        name="quick",
    )


def _label(method: str, bins: int) -> str:
    return {"bins": f"bins {bins}", "reused": f"bins {bins} @0°"}.get(method, method)


def _orders(scene, bin_counts, stale):
    """The draw orders of this view: method label → (method, bins, order)."""
    from hairjax.experimental import draw_order, segment_depth, visibility_order

    _, _, depth, segments, drawable = visibility_order(scene.replace(ordering=_hj().Ordering("none")))
    seg_depth = segment_depth(depth, segments[drawable])
    out = {"exact": ("exact", 0, drawable[draw_order(seg_depth, "exact")])}
    out["static"] = ("static", 0, visibility_order(scene.replace(ordering=_hj().Ordering("static")))[4])
    for n in bin_counts:
        out[_label("bins", n)] = ("bins", n, drawable[draw_order(seg_depth, "bins", n)])
    out[_label("reused", scene.ordering.bins)] = ("reused", scene.ordering.bins, stale)
    out["none"] = ("none", 0, drawable)
    return out


def _timings(name, scene, bin_counts, repeats: int) -> list[dict]:
    from hairjax.experimental import draw_order, hair_centre, segment_depth, static_order, visibility_order
    from hairjax.tools import median_time

    _, _, depth, segments, drawable = visibility_order(scene.replace(ordering=_hj().Ordering("none")))
    seg = segments[drawable]
    points, offsets = scene.strands.points, scene.strands.offsets
    all_segments = scene.strands.segments()
    base = dict(scene=name, segments=len(drawable))

    def sort(method, n=256):
        ordering = _hj().Ordering(method, n) if method == "bins" else _hj().Ordering(method)
        return lambda: draw_order(segment_depth(depth, seg), ordering)

    rows = [
        dict(base, method="exact", bins=0, when="every view", order_s=median_time(sort("exact"), repeats)),
        dict(
            base,
            method="static",
            bins=0,
            when="once",
            order_s=median_time(
                lambda: static_order(points, all_segments, hair_centre(points, offsets)), repeats
            ),
        ),
    ]
    for n in bin_counts:
        rows.append(
            dict(
                base, method="bins", bins=n, when="every view", order_s=median_time(sort("bins", n), repeats)
            )
        )
    n = scene.ordering.bins
    rows.append(
        dict(base, method="reused", bins=n, when="once", order_s=median_time(sort("bins", n), repeats))
    )
    return rows


def _plot(rows, timing_rows, path: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    labels = list(dict.fromkeys(_label(r["method"], r["bins"]) for r in rows))
    lines = ["-", "--", ":", "-."]
    markers = ["o", "s", "^", "D"]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.4))
    for si, scene in enumerate(scenes):
        for li, label in enumerate(labels):
            sel = sorted(
                (r for r in rows if r["scene"] == scene and _label(r["method"], r["bins"]) == label),
                key=lambda r: r["angle"],
            )
            axes[0].plot(
                [r["angle"] for r in sel],
                [r["rmse"] for r in sel],
                color=f"C{li}",
                linestyle=lines[si % 4],
                marker=".",
                label=f"{scene}: {label}",
            )
        for t in timing_rows:
            if t["scene"] != scene or t["method"] == "exact":  # the reference: error 0
                continue
            li = labels.index(_label(t["method"], t["bins"]))
            err = np.median(
                [
                    r["rmse"]
                    for r in rows
                    if r["scene"] == scene and (r["method"], r["bins"]) == (t["method"], t["bins"])
                ]
            )
            once = t["when"] == "once"
            axes[1].scatter(
                t["order_s"],
                err,
                color=f"C{li}",
                marker=markers[si % 4],
                facecolors="none" if once else f"C{li}",
                label=f"{scene}: {_label(t['method'], t['bins'])}",
            )
    axes[0].set_xlabel("camera turned by (degrees)")
    axes[0].set_ylabel("RMSE against the exact order")
    axes[0].set_yscale("log")
    axes[0].legend(fontsize=5, ncol=3)
    axes[1].set_xscale("log")
    axes[1].set_yscale("log")
    axes[1].set_xlabel("time to compute the order (s; hollow: once, filled: every view)")
    axes[1].set_ylabel("median RMSE over the views")
    axes[1].legend(fontsize=5, ncol=2)
    for ax in axes:
        ax.grid(True, alpha=0.3)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _ints(text: str) -> list[int]:
    try:
        values = [int(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected integers separated by commas: {text!r}")
    if not values or min(values) < 1:
        raise argparse.ArgumentTypeError(f"expected positive integers: {text!r}")
    return values


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scenes", default="default,tressfx,head", help=f"among {', '.join(SCENES)}")
    p.add_argument("--size", type=int, default=192, help="image size in pixels (default 192)")
    p.add_argument(
        "--angles",
        type=_angles,
        default=[float(a) for a in range(0, 360, 30)],
        help="degrees, comma-separated (default 0,30,...,330; 0 is always added)",
    )
    p.add_argument(
        "--bins",
        type=_ints,
        default=[16, 64, 256, 1024],
        help="bin counts for the per-view bin sort (default 16,64,256,1024)",
    )
    p.add_argument("--repeats", type=int, default=5, help="timing runs, median (default 5)")
    p.add_argument("--out", type=Path, default=Path("out/static_order"))
    p.add_argument(
        "--quick",
        action="store_true",
        help="a 200-strand ball at 40² without shadows, angles 0,90,180, bins 4,16, 1 timing run",
    )
    return p


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    if args.repeats < 1 or args.size < 4:
        raise SystemExit("--repeats must be at least 1 and --size at least 4")
    hj = _hj()
    from hairjax.experimental import visibility_order

    if args.quick:
        scenes = {"quick": lambda size: quick_scene()}
        args.angles, args.bins, args.repeats = [0.0, 90.0, 180.0], [4, 16], 1
    else:
        unknown = [s for s in args.scenes.split(",") if s not in SCENES]
        if unknown:
            raise SystemExit(f"unknown scene(s) {', '.join(unknown)}; choose from {', '.join(SCENES)}")
        scenes = {k: SCENES[k] for k in args.scenes.split(",")}

    rows, timing_rows, titles = [], [], []
    started = time.perf_counter()
    for name, make in scenes.items():
        scene = make(args.size)
        cam = scene.camera
        titles.append(f"{name}: {scene.strands.num_strands:,} strands, {cam.width}×{cam.height}")
        print(f"scene {titles[-1]}; reused order: {scene.ordering.bins} bins at 0°", flush=True)
        stale = visibility_order(scene.replace(ordering=hj.Ordering("bins", scene.ordering.bins)))[4]
        for angle in args.angles:
            view = turned(scene, angle)
            orders = _orders(view, args.bins, stale)
            # Each render runs the set-up afresh: a given order is never cached.
            reference = np.asarray(hj.render(view, order=orders["exact"][2]))
            line = []
            for label, (method, bins, order) in orders.items():
                if method == "exact":
                    continue
                d = image_difference(np.asarray(hj.render(view, order=order)), reference)
                rows.append(dict(scene=name, method=method, bins=bins, angle=angle, **d))
                line.append(f"{label} {d['rmse']:.1e}")
            print(
                f"  {angle:5.1f}°  rmse: " + ", ".join(line) + f"  ({time.perf_counter() - started:.0f} s)",
                flush=True,
            )
        timing_rows += _timings(name, scene, args.bins, args.repeats)

    from hairjax.experimental import write_csv

    csv_path = args.out / "static_order.csv"
    timings_path = args.out / "static_order_timings.csv"
    png_path = args.out / "static_order.png"
    write_csv(csv_path, CSV_COLUMNS, rows, float_format=".6g")
    write_csv(timings_path, TIMING_COLUMNS, timing_rows, float_format=".6g")
    _plot(
        rows, timing_rows, png_path, "Draw orders against the exact order of each view — " + "; ".join(titles)
    )

    print()
    print(
        f"error against the exact order of each view, over {len(args.angles)} views "
        f"(median / max); order time: median of {args.repeats} run(s) after a warm-up"
    )
    print(
        f"{'scene':<8} {'order':<14} {'computed':<10} {'time':>9} {'RMSE med':>9} {'RMSE max':>9} "
        f"{'max abs':>8} {'>1/255 med':>10} {'>1/255 max':>10}"
    )
    for name in scenes:
        labels = dict.fromkeys((r["method"], r["bins"]) for r in rows if r["scene"] == name)
        for method, bins in labels:
            sel = [r for r in rows if r["scene"] == name and (r["method"], r["bins"]) == (method, bins)]
            t = next(
                (t for t in timing_rows if t["scene"] == name and (t["method"], t["bins"]) == (method, bins)),
                None,
            )
            time_text = "–" if t is None else f"{t['order_s'] * 1e3:.2f} ms"
            when = "" if t is None else t["when"]
            rmse = [r["rmse"] for r in sel]
            vis = [100 * r["frac_visible"] for r in sel]
            print(
                f"{name:<8} {_label(method, bins):<14} {when:<10} {time_text:>9} {np.median(rmse):9.2e} "
                f"{max(rmse):9.2e} {max(r['max_abs'] for r in sel):8.3f} {np.median(vis):9.2f}% "
                f"{max(vis):9.2f}%"
            )
        exact = next(t for t in timing_rows if t["scene"] == name and t["method"] == "exact")
        print(f"{name:<8} {'exact':<14} {'every view':<10} {exact['order_s'] * 1e3:6.2f} ms (the reference)")
    print(f"\nwrote {csv_path}\nwrote {timings_path}\nwrote {png_path}")
    print(f"total {time.perf_counter() - started:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
