"""Deep opacity maps against opacity maps at equal time (docs/results.md §8).

Yuksel & Keyser 2008 ("Deep Opacity Maps") claim that a few layers that start, per texel,
at the first hair the light meets give fewer artefacts than many uniform slices (kim-2003
§4's opacity maps) at a fraction of the time: 3 layers at 114 fps against 81 fps for 16
slices and 2.3 fps for 128. This script measures that claim with this project's numbers.

For each scene, every setting is rendered by the GL renderer (the fast path, the one whose
time the claim is about; `hairjax compare` holds it to the JAX renderer) and measured
against the same scene with `exact` shadows at the same light resolution (Ω at each
point's own depth, docs/model.md §7):
- τ error: RMSE and max of τ = exp(−κΩ) over the strand points (float64);
- image error: RMSE of RGB over the reference image's peak (the sweep's relative RMSE);
- time: the median over `--repeats` renders (after a warm-up that builds the shaders) of
  the shadow pass alone (`GLResult.timings["shadows"]`: light frame, maps or layers, Ω
  per point) and of the whole render.
The summary sets each deep-map setting beside the opacity-map curve at the same shadow
time (log-log interpolation between the two nearest settings). Deep maps are measured with
each of `--lookups` (docs/model.md §7: "layer", the paper's, reads every neighbour texel at
the point's own layer; "depth" reads each at the point's depth behind its own first hair).

    python experiments/16_deep_maps.py --docs docs      # default scene, bear, Sintel
    python experiments/16_deep_maps.py --quick          # tiny, for the test suite
    python experiments/16_deep_maps.py --lookups depth  # deep maps with one lookup only

Writes DIR/deep_maps.csv (one row per scene and setting), DIR/deep_maps.md (the tables),
DIR/deep_maps_<scene>.png (error against time) and DIR/deep_maps_bear.png (the bear's
stripes: opacity maps, deep maps and exact side by side, with each one's difference from
exact); `--docs DIR` copies the figures to DIR/figures/.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import shutil
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
SCENES = ("default", "bear", "sintel")
DEFAULT_MAPS = (4, 8, 16, 32, 64, 128)
DEFAULT_LAYERS = (2, 3, 4, 6, 8)
# Deep layers' spacing Δ as a fraction of the default, the hair's light-depth extent over K
# (docs/model.md §7): 1 spreads the K layers over the whole hair, 1/4 packs them into its
# lit quarter, where Yuksel & Keyser place them (the opacity saturates a few strands in).
DEFAULT_SPACINGS = (1.0, 0.25)
LOOKUPS = ("layer", "depth")
CSV_COLUMNS = (
    "scene",
    "method",
    "count",
    "spacing",
    "lookup",
    "shadow_s",
    "total_s",
    "tau_rmse",
    "tau_max",
    "rel_rmse",
)
# The bear's figure (docs/results.md §8): the artefact a new user sees (stripes across its back
# with the default 64 opacity maps), beside deep maps of this many layers and exact shadows.
FIGURE_MAPS, FIGURE_LAYERS = 64, 4


def _ints(text: str) -> list[int]:
    try:
        values = sorted({int(x) for x in text.split(",") if x.strip()})
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected integers separated by commas: {text!r}") from None
    if not values or values[0] < 1:
        raise argparse.ArgumentTypeError(f"expected positive integers: {text!r}")
    return values


def _fractions(text: str) -> list[float]:
    try:
        values = sorted({float(x) for x in text.split(",") if x.strip()}, reverse=True)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected numbers separated by commas: {text!r}") from None
    if not values or not all(0 < v <= 1 for v in values):
        raise argparse.ArgumentTypeError(f"expected fractions in (0, 1]: {text!r}")
    return values


def _lookups(text: str) -> list[str]:
    values = list(dict.fromkeys(x.strip() for x in text.split(",") if x.strip()))
    if not values or not set(values) <= set(LOOKUPS):
        raise argparse.ArgumentTypeError(f"expected some of {', '.join(LOOKUPS)}: {text!r}")
    return values


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scenes", default=",".join(SCENES), help=f"of {', '.join(SCENES)} (default: all)")
    p.add_argument("--size", type=int, default=256, help="image SIZE × SIZE (default 256)")
    p.add_argument("--resolution", type=int, default=256, help="the light's raster, texels (default 256)")
    p.add_argument("--maps", type=_ints, default=list(DEFAULT_MAPS), help="opacity-map counts N")
    p.add_argument("--layers", type=_ints, default=list(DEFAULT_LAYERS), help="deep-map layer counts K")
    p.add_argument(
        "--spacings",
        type=_fractions,
        default=list(DEFAULT_SPACINGS),
        help="deep layers' spacing as fractions of the hair's light-depth extent over K (default 1,0.25)",
    )
    p.add_argument(
        "--lookups",
        type=_lookups,
        default=list(LOOKUPS),
        help="deep maps' lookups, of layer, depth (default both)",
    )
    p.add_argument("--repeats", type=int, default=3, help="timed renders per setting, median (default 3)")
    p.add_argument("--out", type=Path, default=Path("out/deep_maps"), help="output folder")
    p.add_argument("--docs", type=Path, help="copy the figures into DOCS/figures/")
    p.add_argument("--data", type=Path, default=ROOT.parent / "shared" / "data", help="shared/data")
    p.add_argument("--quick", action="store_true", help="a tiny fur ball, for the test suite")
    return p


def base_scene(name: str, size: int, data: Path):
    """The scene `name` at `size`², before its shadow method is chosen."""
    import hairjax as hj

    if name in ("bear", "sintel") and not (data / "tressfx").is_dir():
        raise SystemExit(f"16_deep_maps: {name} needs the TressFX assets in {data / 'tressfx'}: pass --data")
    if name == "default":
        scene = hj.load_scene(hj.default_scene_path())
    elif name == "bear":
        scene = hj.scene_for_hair(data / "tressfx" / "bear.tfx", width=size, height=size)
    elif name == "sintel":  # her hair with the head mesh, which casts into the maps (§13)
        tressfx = data / "tressfx"
        overrides = {
            "hair.source": str(tressfx / "sintel_hair.tfx"),
            "occluder.path": str(tressfx / "sintel_head.obj"),
        }
        scene = hj.load_scene(ROOT / "experiments" / "scenes" / "sintel.toml", overrides)
    elif name == "tiny":
        scene = hj.load_scene(hj.default_scene_path()).replace(strands=hj.furball(300, 8, seed=2))
    else:
        raise SystemExit(f"16_deep_maps: unknown scene {name!r}; scenes: {', '.join(SCENES)}")
    return scene.replace(camera=dataclasses.replace(scene.camera, width=size, height=size))


def _render(scene, repeats: int):
    """(image, Ω, median shadow-pass seconds, median total seconds): one warm-up, then
    `repeats` timed GL renders."""
    from hairjax.gl import render_gl
    from hairjax.tools import timed_calls

    shadow, warm_up = [], []

    def after(k, result, _seconds):
        if k == 0:
            warm_up.append(result)
        else:
            shadow.append(result.timings["shadows"])

    total = timed_calls(lambda: render_gl(scene), repeats, after).runs_s
    result = warm_up[0]
    return result.image, result.omega, statistics.median(shadow), statistics.median(total)


def light_extent(scene) -> float:
    """The hair's depth extent along a directional light, D_N − D₀ (docs/model.md §7)."""
    if scene.light.kind != "directional":
        raise SystemExit("16_deep_maps: --spacings below 1 need a directional light (the extent along it)")
    direction = np.asarray(scene.light.direction, np.float64)
    depth = np.asarray(scene.strands.points, np.float64) @ (direction / np.linalg.norm(direction))
    return float(depth.max() - depth.min())


def shadows_of(scene, method: str, count: int, spacing: float, lookup: str, resolution: int):
    """The shadow method of one setting: N opacity maps, or K deep layers at `spacing` times
    the default spacing, read with `lookup`."""
    import hairjax as hj

    if method == "opacity-maps":
        return hj.Shadows(method, maps=count, resolution=resolution)
    # 0 is the method's own default, extent / K: passed as is, so the full spacing is the
    # scene file's default exactly.
    delta = 0.0 if spacing == 1.0 else spacing * light_extent(scene) / count
    return hj.Shadows(method, layers=count, resolution=resolution, layer_spacing=delta, lookup=lookup)


def measure(name: str, scene, settings, resolution: int, repeats: int) -> tuple[list[dict], dict]:
    """One row per setting of `settings` (`(method, count, spacing, lookup)`), each against
    exact shadows; and the images by setting (for the figure)."""
    import hairjax as hj

    exact = scene.replace(shadows=hj.Shadows("exact", resolution=resolution))
    ref_image, ref_omega, ref_shadow, ref_total = _render(exact, repeats)
    kappa = float(np.asarray(scene.params.kappa))
    tau_ref = np.exp(-kappa * np.asarray(ref_omega, np.float64))
    rgb_ref = np.asarray(ref_image[..., :3], np.float64)
    peak = float(rgb_ref.max())
    rows = [
        {
            "scene": name,
            "method": "exact",
            "count": "",
            "spacing": "",
            "lookup": "",
            "shadow_s": ref_shadow,
            "total_s": ref_total,
            "tau_rmse": 0.0,
            "tau_max": 0.0,
            "rel_rmse": 0.0,
        }
    ]
    images = {("exact", 0, "", ""): ref_image}
    for method, count, spacing, lookup in settings:
        variant = scene.replace(shadows=shadows_of(scene, method, count, spacing, lookup, resolution))
        image, omega, shadow_s, total_s = _render(variant, repeats)
        dtau = np.exp(-kappa * np.asarray(omega, np.float64)) - tau_ref
        drgb = np.asarray(image[..., :3], np.float64) - rgb_ref
        rows.append(
            {
                "scene": name,
                "method": method,
                "count": count,
                "spacing": spacing,
                "lookup": lookup,
                "shadow_s": shadow_s,
                "total_s": total_s,
                "tau_rmse": float(np.sqrt(np.mean(dtau**2))),
                "tau_max": float(np.abs(dtau).max()),
                "rel_rmse": float(np.sqrt(np.mean(drgb**2))) / peak,
            }
        )
        images[(method, count, spacing, lookup)] = image
        print(
            f"  {name:8s} {method:12s} {count:4d} {spacing or '':>5} {lookup:5s}: "
            f"shadows {1e3 * shadow_s:8.1f} ms, "
            f"τ RMSE {rows[-1]['tau_rmse']:.4f}, image {100 * rows[-1]['rel_rmse']:.3f} %",
            flush=True,
        )
    return rows, images


def at_equal_time(rows: list[dict], scene: str, shadow_s: float, key: str) -> float | None:
    """The opacity-map curve's `key` at shadow time `shadow_s`, interpolated in log-log
    between the two settings whose times bracket it (None outside the curve's range)."""
    curve = sorted(
        (r["shadow_s"], r[key]) for r in rows if r["scene"] == scene and r["method"] == "opacity-maps"
    )
    for (t0, e0), (t1, e1) in zip(curve, curve[1:]):
        if t0 <= shadow_s <= t1 and t1 > t0:
            if e0 <= 0 or e1 <= 0:  # a zero error has no logarithm: interpolate linearly
                return e0 + (e1 - e0) * (shadow_s - t0) / (t1 - t0)
            w = math.log(shadow_s / t0) / math.log(t1 / t0)
            return math.exp((1 - w) * math.log(e0) + w * math.log(e1))
    return None


def summary(rows: list[dict]) -> str:
    """Per scene: every setting, then each deep setting beside opacity maps at its time."""
    lines = [
        "| scene | method | N or K | Δ / default | lookup | shadow pass (ms) | whole render (ms) "
        "| τ RMSE | τ max | image rel. RMSE |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['scene']} | {r['method']} | {r['count']} | {r['spacing']} | {r['lookup']} | "
            f"{1e3 * r['shadow_s']:.1f} | "
            f"{1e3 * r['total_s']:.1f} | {r['tau_rmse']:.4f} | {r['tau_max']:.3f} | "
            f"{100 * r['rel_rmse']:.3f} % |"
        )
    lines += [
        "",
        "Deep maps beside opacity maps at the same shadow-pass time (the opacity-map curve "
        "interpolated in log-log; — where the deep setting is faster or slower than every "
        "opacity-map setting):",
        "",
        "| scene | K | Δ / default | lookup | shadow pass (ms) | deep τ RMSE | opacity maps τ RMSE "
        "| ratio | deep image | opacity maps image |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        if r["method"] != "deep":
            continue
        tau = at_equal_time(rows, r["scene"], r["shadow_s"], "tau_rmse")
        img = at_equal_time(rows, r["scene"], r["shadow_s"], "rel_rmse")
        ratio = "—" if tau is None or r["tau_rmse"] == 0 else f"{tau / r['tau_rmse']:.1f}×"
        lines.append(
            f"| {r['scene']} | {r['count']} | {r['spacing']} | {r['lookup']} | {1e3 * r['shadow_s']:.1f} | "
            f"{r['tau_rmse']:.4f} | "
            f"{'—' if tau is None else f'{tau:.4f}'} | {ratio} | {100 * r['rel_rmse']:.3f} % | "
            f"{'—' if img is None else f'{100 * img:.3f} %'} |"
        )
    return "\n".join(lines)


def plot(path: Path, rows: list[dict], scene: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for ax, key, label in zip(axes, ("tau_rmse", "rel_rmse"), ("τ RMSE against exact", "image RMSE / peak")):
        curves = [("opacity-maps", "", "", "o-", "N", "opacity maps")]
        deep = sorted(
            {(r["spacing"], r["lookup"]) for r in rows if r["method"] == "deep"},
            key=lambda d: (-d[0], LOOKUPS.index(d[1])),
        )
        curves += [
            ("deep", f, lookup, "s-" if lookup == "layer" else "^--", "K", f"deep, Δ × {f:g}, {lookup}")
            for f, lookup in deep
        ]
        for method, spacing, lookup, marker, tag, legend in curves:
            pts = [
                r
                for r in rows
                if r["scene"] == scene
                and r["method"] == method
                and (method != "deep" or (r["spacing"], r["lookup"]) == (spacing, lookup))
            ]
            if not pts:
                continue
            ax.plot([1e3 * r["shadow_s"] for r in pts], [r[key] for r in pts], marker, label=legend)
            for r in pts:
                ax.annotate(f"{tag}={r['count']}", (1e3 * r["shadow_s"], r[key]), fontsize=7)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("GL shadow pass (ms)")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
    fig.suptitle(f"{scene}: deep opacity maps against opacity maps")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _display(image) -> np.ndarray:
    """Linear RGB for the eye: clipped to 0 … 1, gamma 1/2.2 (a figure, not a measurement)."""
    return np.clip(np.asarray(image, np.float64)[..., :3], 0.0, 1.0) ** (1 / 2.2)


def stripes_figure(path: Path, images: dict, lookups: list[str], title: str) -> None:
    """Opacity maps, deep maps (each of `lookups`) and exact side by side (sRGB), each
    one's |difference| from exact below it, ×10."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = [(f"{FIGURE_MAPS} opacity maps", images[("opacity-maps", FIGURE_MAPS, "", "")])]
    panels += [
        (f"deep, {FIGURE_LAYERS} layers, {lookup}", images[("deep", FIGURE_LAYERS, 1.0, lookup)])
        for lookup in lookups
    ]
    panels.append(("exact", images[("exact", 0, "", "")]))
    ref = np.asarray(images[("exact", 0, "", "")][..., :3], np.float64)
    fig, axes = plt.subplots(2, len(panels), figsize=(3.4 * len(panels), 6.8))
    for col, (name, image) in enumerate(panels):
        axes[0, col].imshow(_display(image))
        axes[0, col].set_title(name)
        diff = np.abs(np.asarray(image[..., :3], np.float64) - ref).max(axis=-1)
        axes[1, col].imshow(np.clip(10 * diff, 0, 1), cmap="magma", vmin=0, vmax=1)
        axes[1, col].set_title("|difference from exact| × 10")
    for ax in axes.flat:
        ax.set_axis_off()
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    from hairjax.experimental import write_csv, write_text

    if args.quick:
        scenes, args.size, args.resolution = ["tiny"], 48, 32
        args.maps, args.layers, args.repeats = [4, 16, FIGURE_MAPS], [2, FIGURE_LAYERS], 1
    else:
        scenes = [s.strip() for s in args.scenes.split(",") if s.strip()]
    settings = [("opacity-maps", n, "", "") for n in args.maps]
    settings += [
        ("deep", k, f, lookup) for lookup in args.lookups for f in args.spacings for k in args.layers
    ]
    figure_scene = "tiny" if args.quick else "bear"
    if figure_scene in scenes:  # the figure's settings, measured like the others
        figure = (("opacity-maps", FIGURE_MAPS, "", ""),)
        figure += tuple(("deep", FIGURE_LAYERS, 1.0, lookup) for lookup in args.lookups)
        settings += [s for s in figure if s not in settings]
    args.out.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    rows, figures = [], []
    for name in scenes:
        print(f"{name}: {args.size}², light raster {args.resolution}², {args.repeats} timed renders each")
        scene = base_scene(name, args.size, args.data)
        scene_rows, images = measure(name, scene, settings, args.resolution, args.repeats)
        rows += scene_rows
        figure = args.out / f"deep_maps_{name}.png"
        plot(figure, rows, name)
        figures.append(figure)
        if name == figure_scene:
            stripes = args.out / f"deep_maps_{'bear' if name == 'bear' else name}_stripes.png"
            title = f"{name} at {args.size}², light raster {args.resolution}²"
            stripes_figure(stripes, images, args.lookups, title)
            figures.append(stripes)
    text = summary(rows)
    write_csv(args.out / "deep_maps.csv", CSV_COLUMNS, rows, float_format=".6g")
    write_text(args.out / "deep_maps.md", text + "\n")
    if args.docs is not None:
        (args.docs / "figures").mkdir(parents=True, exist_ok=True)
        for path in figures:
            shutil.copyfile(path, args.docs / "figures" / path.name)
    print()
    print(text)
    print(f"wrote {args.out / 'deep_maps.csv'}, deep_maps.md, {len(figures)} figure(s)")
    print(f"total {time.perf_counter() - started:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
