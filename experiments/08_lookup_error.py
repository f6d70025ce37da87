"""Lookup-table Kajiya-Kay against the formula: image error and run time by table size.

wenzel-2002 shades hair from a 2-D texture indexed by (L·T, V·T) (Heidrich–Seidel;
docs/model.md §14). This renders a scene (default: the built-in fur ball at 128 × 128)
with `shading.model = "kajiya-kay-lookup"` for each table size n and compares it with the
analytic `"kajiya-kay"` image of the same renderer: RMSE and largest difference over the
RGB channels, and the median time of the shading stage (JAX: the geometry stage is
computed once and reused, so the time is the table's build plus the shading; GL with
`--gl`: the whole `render_gl` call, the table's build and upload included). Each timed
figure is a median of `--repeats` runs after one warm-up run (compilation).

    python experiments/08_lookup_error.py [--scene PATH] [--size 128] [--sizes 4,8,...,1024]
        [--repeats 3] [--gl] [--out out/lookup_error]

Writes DIR/lookup_error.csv and DIR/lookup_error.png, and prints a table.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np

from hairjax.tools import image_stats, median_time

DEFAULT_SIZES = (4, 8, 16, 32, 64, 128, 256, 512, 1024)
CSV_COLUMNS = (
    "size",
    "rmse",
    "max_abs",
    "shading_s",
    "analytic_shading_s",
    "gl_rmse",
    "gl_max_abs",
    "gl_render_s",
    "gl_analytic_render_s",
)


def _parse_sizes(text: str) -> list[int]:
    try:
        sizes = [int(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"--sizes takes integers separated by commas: {text!r}")
    if not sizes or any(not 2 <= n <= 4096 for n in sizes):
        raise argparse.ArgumentTypeError(f"--sizes takes table sizes in [2, 4096]: {text!r}")
    return sorted(set(sizes))


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scene", type=Path, help="scene TOML (default: the built-in default scene)")
    p.add_argument("--size", type=int, default=128, help="render at SIZE × SIZE (default 128)")
    p.add_argument(
        "--sizes",
        type=_parse_sizes,
        default=list(DEFAULT_SIZES),
        help="table sizes n, comma-separated (default 4,8,...,1024)",
    )
    p.add_argument("--repeats", type=int, default=3, help="timed runs per size, median (default 3)")
    p.add_argument("--gl", action="store_true", help="also measure the GL renderer")
    p.add_argument(
        "--out", type=Path, default=Path("out/lookup_error"), help="output folder (default out/lookup_error)"
    )
    return p


def errors(image, reference) -> tuple[float, float]:
    """RMSE and largest absolute difference over the RGB channels."""
    stats = image_stats(np.asarray(image)[..., :3], np.asarray(reference)[..., :3])
    return stats["rmse"], stats["max_abs"]


def measure(scene, sizes, repeats: int, gl: bool) -> list[dict]:
    """One row per table size (see the module docstring)."""
    import jax

    import hairjax as hj

    analytic = scene.replace(shading=hj.KajiyaKay(scene.params))
    geometry = hj.geometry_stage(analytic)
    shade = lambda g: jax.block_until_ready(hj.shading_stage(g, scene.params))  # noqa: E731
    reference = np.asarray(shade(geometry))
    analytic_s = median_time(lambda: shade(geometry), repeats)
    if gl:
        from hairjax.gl import render_gl

        omega = None if geometry.omega is None else np.asarray(geometry.omega)
        gl_reference = render_gl(analytic, omega=omega).image
        gl_analytic_s = median_time(lambda: render_gl(analytic, omega=omega), repeats)
    rows = []
    for n in sizes:
        lookup = dataclasses.replace(geometry, shading=hj.KajiyaKayLookup(scene.params, size=n))
        image = np.asarray(shade(lookup))
        rmse, max_abs = errors(image, reference)
        row = dict(
            size=n,
            rmse=rmse,
            max_abs=max_abs,
            shading_s=median_time(lambda: shade(lookup), repeats),
            analytic_shading_s=analytic_s,
        )
        if gl:
            lookup_scene = scene.replace(shading=hj.KajiyaKayLookup(scene.params, size=n))
            image = render_gl(lookup_scene, omega=omega).image
            row["gl_rmse"], row["gl_max_abs"] = errors(image, gl_reference)
            row["gl_render_s"] = median_time(lambda: render_gl(lookup_scene, omega=omega), repeats)
            row["gl_analytic_render_s"] = gl_analytic_s
        rows.append(row)
        print(f"  n = {n:5d}: RMSE {rmse:.3g}", file=sys.stderr, flush=True)
    return rows


def format_table(rows, gl: bool) -> str:
    head = f"{'n':>6} {'RMSE':>10} {'max':>10} {'shading':>10}"
    if gl:
        head += f" {'GL RMSE':>10} {'GL max':>10} {'GL render':>10}"
    lines = [head]
    for r in rows:
        line = f"{r['size']:>6} {r['rmse']:>10.3g} {r['max_abs']:>10.3g} {r['shading_s'] * 1e3:>8.2f}ms"
        if gl:
            line += f" {r['gl_rmse']:>10.3g} {r['gl_max_abs']:>10.3g} {r['gl_render_s'] * 1e3:>8.2f}ms"
        lines.append(line)
    tail = f"analytic Kajiya-Kay: shading {rows[0]['analytic_shading_s'] * 1e3:.2f} ms"
    if gl:
        tail += f", GL render {rows[0]['gl_analytic_render_s'] * 1e3:.2f} ms"
    return "\n".join(lines + [tail])


def plot(rows, path: Path, gl: bool) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from hairjax.experimental import atomic_path

    n = [r["size"] for r in rows]
    fig, ax = plt.subplots(figsize=(5.5, 4))
    ax.loglog(n, [r["rmse"] for r in rows], "o-", label="JAX RMSE")
    ax.loglog(n, [r["max_abs"] for r in rows], "s--", label="JAX max")
    if gl:
        ax.loglog(n, [r["gl_rmse"] for r in rows], "x:", label="GL RMSE")
    ax.set_xlabel("table size n (n × n texels)")
    ax.set_ylabel("difference from analytic Kajiya-Kay")
    ax.set_title("Lookup-table shading error (docs/model.md §14)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    with atomic_path(path, ".png") as tmp:
        fig.savefig(tmp, format="png", dpi=120)
    plt.close(fig)


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    import hairjax as hj
    from hairjax.experimental import write_csv

    scene = hj.load_scene(args.scene or hj.default_scene_path())
    camera = dataclasses.replace(scene.camera, width=args.size, height=args.size)
    scene = scene.replace(camera=camera)
    rows = measure(scene, args.sizes, args.repeats, args.gl)
    print(format_table(rows, args.gl))
    args.out.mkdir(parents=True, exist_ok=True)
    print(f"wrote {write_csv(args.out / 'lookup_error.csv', CSV_COLUMNS, rows, '.6g')}")
    plot(rows, args.out / "lookup_error.png", args.gl)
    print(f"wrote {args.out / 'lookup_error.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
