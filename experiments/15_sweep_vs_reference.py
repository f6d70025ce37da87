"""Error against run time, against the physically based reference (docs/physically_based.md §2,
"Quality settings against the physically based reference"): which quality settings still
matter once the model's own error is counted, and what Mitsuba itself costs.

    python experiments/15_sweep_vs_reference.py            # fur ball, 3,000 strands at 128² (~20 min)
    python experiments/15_sweep_vs_reference.py --quick    # a tiny one, seconds (the test's)

1. Mitsuba 3 renders the scene's strands (`hj.reference_image`, blonde fibres) at `--spp`:
   the target; a second seed gives its own noise, which every error includes.
2. Kajiya-Kay (kd, ks, shininess, κ, ambient and the strands' opacity) is fitted to it at
   the scene's quality settings.
3. `hairjax.tools.run_sweep(..., target=)` sweeps the quality knobs (maps, map resolution,
   bins, ribbon width, supersampling) at the fitted parameters, both renderers, every point
   measured against the Mitsuba image: the cheapest settings within 10 % of the best error.
4. Mitsuba's own cost: time against noise at 4 … 256 samples per pixel, its noise the
   RMSE between two sample seeds over √2 (one image's), relative to the target's peak as
   the sweep's errors are, on the same plot.

Outputs in `--out`: the sweep's files (points.jsonl, sweep.csv, summary.md, pareto.png),
`mitsuba_cost.csv`, `fit.json` and `against_reference.png` (both curves on one plot).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import hairjax as hj
from hairjax.experimental import write_csv, write_json
from hairjax.tools import KNOBS, QUICK_KNOBS, run_sweep, write_report

NAMES = ("kd", "ks", "shininess", "kappa", "ambient", "alpha")
QUICK_NAMES = ("kd", "ks", "kappa")  # --quick: no searched α (its step compiles for ~15 s)
BLONDE = hj.ReferenceSettings(eumelanin=0.3, pheomelanin=0.1, longitudinal_roughness=0.3)


def scene_of(strands: int, size: int, maps: int) -> hj.Scene:
    overrides = {
        "hair.strands": strands,
        "hair.points": 8,
        "camera.width": size,
        "camera.height": size,
        "shadows.maps": maps,
        "shadows.resolution": 2 * size,
    }
    return hj.load_scene(hj.default_scene_path(), overrides).replace(reference=BLONDE, name="furball")


def mitsuba_cost(scene: hj.Scene, spps, peak: float) -> list[dict]:
    """Per spp: one render's time and its noise (RMSE between seeds 1 and 2, over √2)."""
    rows = []
    for spp in spps:
        start = time.perf_counter()
        a = hj.reference_image(scene, spp=spp, seed=1)
        elapsed = time.perf_counter() - start
        b = hj.reference_image(scene, spp=spp, seed=2)
        noise = float(np.sqrt(np.mean((a[..., :3].astype(np.float64) - b[..., :3]) ** 2) / 2))
        rows.append({"spp": spp, "time_s": elapsed, "noise_rmse": noise, "rel_noise": noise / peak})
    return rows


def plot(points: list[dict], cost: list[dict], best_fit: float, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5), dpi=110)
    for renderer, style in (("jax", "-o"), ("gl", "--s")):
        mine = [p for p in points if p["path"] == renderer and "skipped" not in p]
        for knob in dict.fromkeys(p["knob"] for p in mine):
            curve = sorted((p["time_s"], p["rel_rmse"]) for p in mine if p["knob"] == knob)
            ax.plot(*zip(*curve), style, ms=3, lw=1, label=f"{renderer} {knob}")
    ax.plot(
        [c["time_s"] for c in cost],
        [c["rel_noise"] for c in cost],
        "k-^",
        lw=1.5,
        label="Mitsuba noise (spp)",
    )
    for c in cost:
        ax.annotate(
            str(c["spp"]),
            (c["time_s"], c["rel_noise"]),
            fontsize=7,
            xytext=(3, 3),
            textcoords="offset points",
        )
    ax.axhline(best_fit, color="grey", lw=0.8, ls=":", label="fit's error at the scene's settings")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("render time (s)")
    ax.set_ylabel("RMSE / target peak")
    ax.set_title("Error against run time, against Mitsuba's hair BSDF")
    ax.legend(fontsize=6, ncol=2)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--strands", type=int, default=3000)
    p.add_argument("--size", type=int, default=128)
    p.add_argument("--spp", type=int, default=2048, help="the target's samples per pixel")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--paths", default="jax,gl")
    p.add_argument("--quick", action="store_true", help="a tiny scene and few knob values (seconds)")
    p.add_argument("--out", type=Path, default=Path("out/sweep_vs_reference"))
    args = p.parse_args(argv)
    if args.quick:
        args.strands, args.size, args.spp, args.repeats, args.paths = 60, 24, 16, 1, "jax"
    knobs = {k: QUICK_KNOBS[k][:2] for k in ("maps", "bins")} if args.quick else KNOBS
    scene = scene_of(args.strands, args.size, 4 if args.quick else 32)
    args.out.mkdir(parents=True, exist_ok=True)

    start = time.perf_counter()
    target = hj.reference_image(scene, spp=args.spp, seed=0)
    target_s = time.perf_counter() - start
    peak = float(target[..., :3].max())
    # The target's own noise: one image's RMSE from a second seed's (over √2). Every error
    # against the target includes it (in quadrature); it is what no setting can go below.
    second = hj.reference_image(scene, spp=args.spp, seed=3)
    floor = float(np.sqrt(np.mean((target[..., :3].astype(np.float64) - second[..., :3]) ** 2) / 2))
    print(
        f"target: Mitsuba at {args.spp} spp, {args.size}², {args.strands} strands, {target_s:.1f} s; "
        f"its noise {floor / peak:.3g} of the peak"
    )

    fit = hj.fit(
        scene,
        target,
        variables=QUICK_NAMES if args.quick else NAMES,
        stop=hj.FitStop(max_steps=5 if args.quick else 100),
    )
    alpha = scene.strands.alpha if fit.alpha is None else np.full(scene.strands.num_strands, fit.alpha)
    fitted = scene.replace(params=fit.params, strands=scene.strands.replace(alpha=alpha))
    write_json(args.out / "fit.json", {**fit.to_json(), "target_noise_rmse": floor, "target_peak": peak})
    opacity = "held" if fit.alpha is None else f"{fit.alpha:.3g}"
    print(f"fit: RMSE {fit.rmse:.4g} ({fit.rmse / peak:.3g} of the peak), alpha {opacity}, {fit.termination}")

    paths = tuple(x.strip() for x in args.paths.split(",") if x.strip())
    points = run_sweep(
        fitted, args.out, knobs=knobs, paths=paths, repeats=args.repeats, progress=None, target=target
    )
    config = json.loads((args.out / "sweep.json").read_text())
    write_report(args.out, points, config)

    spps = [s for s in (4, 16, 64, 256) if s <= args.spp]
    cost = mitsuba_cost(scene, spps, peak)
    write_csv(args.out / "mitsuba_cost.csv", ["spp", "time_s", "noise_rmse", "rel_noise"], cost)
    plot(points, cost, fit.rmse / peak, args.out / "against_reference.png")

    print((args.out / "summary.md").read_text().split("## All points")[0].rstrip())
    print("\nMitsuba's own cost (noise = one image's RMSE from the seed-to-seed difference):")
    for c in cost:
        print(f"  {c['spp']:5d} spp  {c['time_s']:7.2f} s  noise {c['rel_noise']:.3g} of the peak")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
