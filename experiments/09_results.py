"""Regenerate docs/results.md: error against run time, kim-2003's claims, stiff fits.

    .venv/bin/python experiments/09_results.py [--size 256] [--repeats 3] [--joint-size 512]

runs, each into out/results/<name>/ (the sweep resumes if cut short):
- `hairjax sweep` of the default scene (both paths, all knobs) at --size;
- kim-2003 Fig. 16, `experiments/05_maps_vs_time.py` (GL time against N maps, ± §4.2 clipping);
- kim-2003 Fig. 8, `experiments/06_order_reuse.py` (an order reused while the head turns);
- kim-2003 §3, ordering throughput against kim-2003's 0.7 M lines/s (§6, a Pentium III);
- `experiments/03_stiff_fits.py` (each solver on stiff and degenerate fits);
- the distillation's per-view table, quoted from docs/physically_based.md (not rerun);
- `hairjax sweep --joint` of the default scene (both paths, `JOINT_KNOBS`) at --joint-size,
  the cheapest combination of settings per error (it resumes too);
- `experiments/16_deep_maps.py` (deep opacity maps against opacity maps at equal time);
then copies the figures to docs/figures/ and writes docs/results.md. `--quick` runs tiny
versions and writes into --docs (the test suite's smoke run).
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import importlib.util
import io
import json
import shutil
import sys
import time
from contextlib import redirect_stdout
from pathlib import Path

import hairjax as hj
from hairjax.tools import (
    JOINT_KNOBS,
    KNOBS,
    QUICK_JOINT_KNOBS,
    QUICK_KNOBS,
    SearchConfig,
    load_points,
    median_time,
    run_joint,
    run_sweep,
    summary_markdown,
    write_report,
    write_text,
)

ROOT = Path(__file__).resolve().parents[1]
KIM_2003_LINES_PER_S = 0.7e6  # kim-2003 §3/§6, a 700 MHz Pentium III


def _experiment(name: str):
    spec = importlib.util.spec_from_file_location(name, ROOT / "experiments" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _run(name: str, argv: list[str]) -> str:
    """Run an experiment's main(argv) and return what it printed."""
    buf = io.StringIO()
    with redirect_stdout(buf):
        code = _experiment(name).main(argv)
    if code:
        raise SystemExit(f"experiments/{name}.py {' '.join(argv)} failed with exit code {code}")
    return buf.getvalue()


def _csv(path: Path) -> list[dict]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _table(rows: list[dict], columns: list[str]) -> str:
    def cell(v):
        try:
            return f"{float(v):.3g}"
        except (TypeError, ValueError):
            return str(v)

    lines = ["| " + " | ".join(columns) + " |", "|---" * len(columns) + "|"]
    lines += ["| " + " | ".join(cell(r.get(c, "")) for c in columns) + " |" for r in rows]
    return "\n".join(lines)


def distillation_summary(docs: Path) -> str:
    """docs/physically_based.md §1's per-view table: the real-time models fitted to Mitsuba's
    hair (experiments/14_distill.py, whose full run takes 35 minutes and is not rerun here),
    or a pointer to the page where it has no such table (a fresh `--docs` folder)."""
    page = docs / "physically_based.md"
    lines = page.read_text().splitlines() if page.exists() else []
    start = next((i for i, line in enumerate(lines) if line.startswith("Per view, median")), None)
    if start is None:
        return "Not yet run: `python experiments/14_distill.py --docs docs` (docs/physically_based.md §1)."
    table = []
    for line in lines[start + 1 :]:
        if line.startswith("|"):
            table.append(line)
        elif table:  # the first line after the table ends it
            break
    return "\n".join([lines[start], "", *table])


def ordering_throughput(strand_counts, points: int, repeats: int) -> list[dict]:
    """Depth-bin ordering (256 bins) on fur balls seen by the default camera."""
    camera = hj.load_scene(hj.default_scene_path()).camera
    rows = []
    for n in strand_counts:
        strands = hj.furball(n, points, seed=0)
        _, depth = hj.experimental.camera_view(camera).project(strands.points)
        segments = strands.segments()
        median = median_time(
            lambda: hj.experimental.draw_order(hj.experimental.segment_depth(depth, segments), "bins", 256),
            repeats,
        )
        rate = len(segments) / median
        rows.append(
            {
                "strands": n,
                "segments": len(segments),
                "median_ms": 1e3 * median,
                "M segments/s": rate / 1e6,
                "× kim-2003": rate / KIM_2003_LINES_PER_S,
            }
        )
    return rows


def joint_section(
    scene: hj.Scene, out: Path, figures: Path, repeats: int, budget_s: float | None, quick: bool
) -> str:
    """Section 7: the joint search of `scene` into `out`, its plot copied to `figures`."""
    started = time.perf_counter()
    knobs = QUICK_JOINT_KNOBS if quick else JOINT_KNOBS

    def progress(done: int, total: int, message: str = "") -> None:  # a line per point: it runs an hour
        print(f"joint search: {done}/{total} {message}", file=sys.stderr, flush=True)

    search = SearchConfig(budget_s=budget_s)
    points = run_joint(
        scene, out, knobs=knobs, repeats=repeats, search=search, progress=None if quick else progress
    )
    config = json.loads((out / "joint.json").read_text())
    files = write_report(out, points, config)
    shutil.copy(files["plot"], figures / "joint_pareto.png")
    # Without its title; its sections one level down, under this one.
    summary = summary_markdown(points, config).split("\n", 2)[2].replace("\n## ", "\n### ")
    size = f"{scene.camera.width}×{scene.camera.height}"
    return f"""## 7. The cheapest combination of settings (`hairjax sweep --joint`)

Section 1 turns one knob at a time, so each curve levels off at the error of the knobs it
holds fixed. `hairjax sweep --joint` searches their combinations instead (the shadow
method and its options, bins, ribbon width, supersampling) for the Pareto front of error
against time, per renderer: a greedy descent from the cheapest setting to 0.05 % error,
taking the step with the largest error reduction per added second, then a Pareto local
search closing the front above it (`hairjax/tools/_pareto.py`). The same engine as section
1's sweep (`hairjax/tools/_search.py`), over another space: each point is measured, stored
and reported as there, against the same reference. `{scene.name}` ({scene.strands.num_strands} strands)
at {size}, timed renders per point: {repeats}; this step took {time.perf_counter() - started:.0f} s
(for a resumed run, the time since it resumed).

![joint search](figures/joint_pareto.png)

{summary}"""


def deep_verdict(rows: list[dict], at_equal_time) -> str:
    """How many deep-map settings beat the opacity-map curve at their own shadow-pass time,
    counted from the run's rows (`at_equal_time` is experiment 16's interpolation)."""
    compared = beaten = 0
    for r in rows:
        if r["method"] != "deep":
            continue
        curve = at_equal_time(rows, r["scene"], float(r["shadow_s"]), "tau_rmse")
        if curve is not None:
            compared += 1
            beaten += float(r["tau_rmse"]) < curve
    return (
        f"Of the {compared} deep-map settings whose shadow-pass time lies within the opacity-map "
        f"curve's, {beaten} have a lower τ RMSE than opacity maps at the same time."
    )


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--size", type=int, default=256, help="sweep image SIZE × SIZE (default 256)")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--out", type=Path, default=ROOT / "out" / "results")
    p.add_argument("--docs", type=Path, default=ROOT / "docs")
    p.add_argument("--joint-size", type=int, default=512, help="joint search image SIZE × SIZE (default 512)")
    p.add_argument(
        "--joint-budget-s", type=float, help="joint search: at most so many seconds measuring per renderer"
    )
    p.add_argument("--quick", action="store_true", help="tiny versions, for the test suite")
    args = p.parse_args(argv)
    out, docs = args.out, args.docs
    figures = docs / "figures"
    figures.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()

    # 1. The sweep.
    scene = hj.load_scene(hj.default_scene_path())
    size = 48 if args.quick else args.size
    if args.quick:
        scene = scene.replace(strands=hj.furball(300, 8, seed=2), shadows=hj.Shadows("opacity-maps", 8, 32))
    scene = scene.replace(camera=dataclasses.replace(scene.camera, width=size, height=size))
    knobs = QUICK_KNOBS if args.quick else KNOBS
    repeats = 1 if args.quick else args.repeats
    points = run_sweep(scene, out / "sweep", knobs=knobs, repeats=repeats, progress=sys.stderr.isatty())
    config = json.loads((out / "sweep" / "sweep.json").read_text())
    files = write_report(out / "sweep", points, config)
    shutil.copy(files["plot"], figures / "sweep_pareto.png")
    summary = summary_markdown(points, config).split("\n", 2)[2]  # without its title

    # 2. kim-2003 Fig. 16.
    maps = "1,4,16" if args.quick else "1,2,4,8,16,32,64,128,256,512"
    maps_out = out / "maps_vs_time"
    scene_arg = []
    if args.quick:  # a small fur ball instead of the default scene
        tiny = out / "tiny.toml"
        tiny.parent.mkdir(parents=True, exist_ok=True)
        tiny.write_text(
            'name = "tiny"\n[hair]\nsource = "furball"\nstrands = 300\npoints = 8\n'
            "[camera]\nwidth = 48\nheight = 48\n"
            '[shadows]\nmethod = "opacity-maps"\nresolution = 32\n'
        )
        scene_arg = ["--scene", str(tiny)]
    maps_printed = _run(
        "05_maps_vs_time", ["--maps", maps, "--repeats", str(repeats), "--out", str(maps_out), *scene_arg]
    )
    shutil.copy(maps_out / "maps_vs_time.png", figures / "maps_vs_time.png")

    # 3. kim-2003 Fig. 8.
    order_out = out / "order_reuse"
    order_args = ["--quick"] if args.quick else ["--repeats", str(repeats)]
    _run("06_order_reuse", order_args + ["--out", str(order_out)])
    shutil.copy(order_out / "order_reuse.png", figures / "order_reuse.png")
    order_rows = _csv(order_out / "order_reuse.csv")
    timing_rows = _csv(order_out / "order_reuse_timings.csv")

    # 4. kim-2003 §3.
    throughput = ordering_throughput((300, 1000) if args.quick else (20_000, 100_000), 16, repeats)

    # 5. Stiff fits.
    stiff_out, searched_out = out / "stiff_fits", out / "stiff_fits_searched"
    quick = ["--quick"] if args.quick else []
    _run("03_stiff_fits", quick + ["--out", str(stiff_out)])
    _run("03_stiff_fits", quick + ["--no-separable", "--out", str(searched_out)])
    stiff_table = (stiff_out / "stiff_fits.md").read_text()
    searched_table = (searched_out / "stiff_fits.md").read_text()

    # 7. The joint search.
    joint_scene = scene  # the quick scene at 48², or the default scene at --joint-size
    if not args.quick:
        camera = dataclasses.replace(scene.camera, width=args.joint_size, height=args.joint_size)
        joint_scene = scene.replace(camera=camera)
    joint = joint_section(joint_scene, out / "joint", figures, repeats, args.joint_budget_s, args.quick)

    # 8. Deep opacity maps against opacity maps.
    deep_out = out / "deep_maps"
    deep_args = ["--quick"] if args.quick else ["--repeats", str(repeats)]
    _run("16_deep_maps", deep_args + ["--out", str(deep_out)])
    for png in deep_out.glob("deep_maps_*.png"):
        shutil.copy(png, figures / png.name)
    deep_rows = [
        {**r, "shadow_s": float(r["shadow_s"]), "tau_rmse": float(r["tau_rmse"])}
        for r in _csv(deep_out / "deep_maps.csv")
    ]
    deep_scenes = list(dict.fromkeys(r["scene"] for r in deep_rows))
    stripes = "deep_maps_tiny_stripes.png" if args.quick else "deep_maps_bear_stripes.png"
    deep_table = (deep_out / "deep_maps.md").read_text().strip()
    deep_plots = "\n".join(f"![deep maps, {s}](figures/deep_maps_{s}.png)" for s in deep_scenes)
    verdict = deep_verdict(deep_rows, _experiment("16_deep_maps").at_equal_time)

    command = "python experiments/09_results.py" + (
        " --quick"
        if args.quick
        else f" --size {args.size} --repeats {args.repeats} --joint-size {args.joint_size}"
        + ("" if args.joint_budget_s is None else f" --joint-budget-s {args.joint_budget_s:g}")
    )
    text = f"""# Results

Regenerated by `{command}` (from the repository root, with the package installed:
`make test` or `make run` install it into `.venv`), which writes its raw tables into
`out/results/` and the figures into `docs/figures/`. Machine: the run's own; times are
medians and only comparable within one run. This run took {time.perf_counter() - started:.0f} s.

## 1. Error against run time (`hairjax sweep`)

`hairjax sweep` of the default scene (`hairjax/scenes/default.toml`) at {size}×{size}:

![Pareto plot](figures/sweep_pareto.png)

{summary}
## 2. kim-2003 Fig. 16: time against the number of opacity maps

`experiments/05_maps_vs_time.py` (GL path, default scene): without §4.2 clipping every
segment is drawn into every map and the time grows linearly in N; with clipping each
segment is drawn only into the slices its depth range meets, and it grows sub-linearly.

![maps vs time](figures/maps_vs_time.png)

```
{maps_printed.strip()}
```

## 3. kim-2003 Fig. 8: one visibility order while the head turns

`experiments/06_order_reuse.py`: the order computed for the camera at 0° is reused as the
camera turns about the hair's vertical axis; the error is against the order recomputed
for each view.

![order reuse](figures/order_reuse.png)

{_table(order_rows, list(order_rows[0]))}

Timings:

{_table(timing_rows, list(timing_rows[0]))}

## 4. kim-2003 §3: ordering throughput

Depth-bin ordering (256 bins, NumPy) of fur balls of 16-point strands, against kim-2003's
0.7 million lines per second:

{_table(throughput, list(throughput[0]))}

## 5. Stiff fits

`experiments/03_stiff_fits.py`: each solver on needle-thin highlights, saturated shadows,
Ks ≈ 0 and starts two orders of magnitude off. As `hj.fit` runs by default: Kd and Ks
solved for at every step, the solver searching the shininess and κ (variable projection,
docs/fitting.md), convergence confirmed by the Gauss-Newton test, with a restart when the
solver's own test passes short of it or when it stops where p has no effect:

{stiff_table.strip()}

For comparison, the solver searching all four parameters (`--no-separable`,
`hj.FitVariables(separable=False)`, Kd and Ks through a softplus). From the start 100× off every
solver ends with Ks in the softplus's flat tail, where neither Ks nor p has an effect on
the image: a stationary point that the convergence test accepts, and the reason variable
projection is the default:

{searched_table.strip()}

## 6. The real-time models against physically based hair

Kajiya-Kay (seed and mirror cone), Scheuermann and Marschner (with and without dual
scattering) fitted by `hj.distill` to Mitsuba 3's hair BSDF (Chiang et al. 2016,
docs/reference.md) on the same strands: 3 assets × 4 melanin colours × 2 longitudinal
roughnesses, three training views and one held-out view and light, each RMSE beside the
reference's own noise floor (two sample seeds). Quoted from docs/physically_based.md §1,
which has the full table, the figures (target | fit | residual), where the models cannot
follow (back light through TT, multiple scattering in light hair) and its command (`python
experiments/14_distill.py --docs docs`, 34 minutes):

{distillation_summary(docs)}

Target | fit | residual on the back-lit view, where every model falls furthest behind
(transmission through the fibres, Marschner's TT lobe, has no term in either model):

![fur ball, blonde, back-lit view](figures/distill_furball_blonde_0.4_back-lit.png)

{joint}

## 8. Deep opacity maps against opacity maps at equal time

Yuksel & Keyser 2008 ("Deep Opacity Maps") claim that a few layers starting, per texel, at
the first hair the light meets give fewer artefacts than many uniform slices at a fraction
of the time (3 layers at 114 fps against 81 fps for 16 slices and 2.3 fps for 128).
`experiments/16_deep_maps.py` renders each setting with the GL renderer and measures τ =
exp(−κΩ) at every strand point and the image against `exact` shadows at the same light
resolution, beside the GL shadow pass's median time (docs/model.md §7 defines both
methods; "layer" reads every neighbour texel at the point's layer as the paper does,
"depth" at the point's depth behind each texel's own first hair). {verdict}

{deep_plots}

The stripes that 64 opacity maps leave across TressFX's bear (slice planes crossing its
thin shell of fur), deep maps of 4 layers with each lookup, and exact shadows, with each
one's difference from exact:

![the bear's stripes](figures/{stripes})

{deep_table}
"""
    write_text(docs / "results.md", text)
    print(f"wrote {docs / 'results.md'} ({len(load_points(out / 'sweep'))} sweep points)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
