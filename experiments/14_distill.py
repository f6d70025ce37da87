"""Distillation: the real-time hair models fitted to Mitsuba 3's physically based hair.

Which real-time parameters reproduce physically based hair, and how much error remains
(docs/reference.md, docs/fitting.md; the table and discussion: docs/physically_based.md §1). Every
target is `hj.reference_image`: the same strands as fibres with Chiang et al. 2016's hair
BSDF, path traced by Mitsuba 3 (`max_depth` 16, so the light scattered between fibres is
in it). Swept:

- hair colours by melanin (`COLOURS`; pbrt-v3 and Mitsuba's `hair` plugin's examples:
  eumelanin 0.3 blonde, 1.3 brown with pheomelanin 0.2 (the plugin's default), 8 black;
  and a pheomelanin-dominant red, eumelanin 0.1 with pheomelanin 1.2, our choice);
- longitudinal roughness β_m 0.2 and 0.4 (`ROUGHNESSES`; azimuthal roughness 0.3, the
  plugin's default);
- three assets (`ASSETS`): the procedural fur ball, AMD's TressFX ponytail, Sintel's
  hair with her head as a mesh occluder (experiments/scenes/*.toml; the hair files are
  read from `--data`, shared/data beside the checkout);
- the real-time models (`MODELS`): Kajiya-Kay with the seed's retro-reflection cone
  (`hj.KajiyaKay`), with the specular (mirror) cone of a cylinder (`hj.KajiyaKayMirror`,
  docs/model.md §8), Scheuermann's two shifted highlights (`hj.Scheuermann`, §17), and
  the Marschner-family fibre (`hj.Marschner`, §19), with and without dual scattering
  (`marschner`, `marschner-dual`), whose fitted pigments and β_m are tabled against the
  reference's (the recovery table).

Each target is one `hj.distill` per model (docs/physically_based.md §4), its references
rendered by the first and reused by the others. Per asset there are four views
(`hj.experimental.DISTILL_VIEWS`): three train one fit (the asset's camera under its key light, the
camera turned 60° about its up vector under the same light, and the first camera under a
back light, which travels towards the eye from behind and above the hair), and one is
held out: a camera turned −50° under a side light, a view and a light the fit never saw.
Every model is fitted to the same targets, from the same start (`STARTS`), with
`hj.fit`'s defaults (Levenberg-Marquardt, the gains solved for by variable projection).
The fitted names are `FIT_NAMES`, one tuple per model; a name every model fits is in
`SHARED_NAMES` (one edit adds the strand opacity `alpha` once `hj.fit` takes it;
`ambient` is not fittable today, and is held at 0, as the reference has no ambient
light).

Real-time settings, not fitted: the strands are opaque (alpha 1: fibres are opaque tubes,
and the ribbons then cover what the fibres do), white (the fitted gains carry the
colour), 1 px wide as the fibres are (docs/reference.md, "The mapping"), 32 opacity maps;
Scheuermann's shift texture and noise mask are off (`shift_noise = mask_noise = 0`): the
fibres have neither.

The noise floor: every target is rendered at two sampler seeds (0, the target, and 1);
the floor is the RMSE between them, pooled over the training views and on the held-out
view, the same definition as the fit's RMSE (√(Σ (a − b)² / 3N) over all pixels, RGB).
Independent noise of variance σ² per channel adds σ² = floor²/2 to a perfect model's
squared RMSE, so floor/√2 is the share of a fit's RMSE that no model can remove.

    python experiments/14_distill.py --docs docs    # the full sweep (docs/physically_based.md §1)
    python experiments/14_distill.py --quick        # tiny, for the test suite
    python experiments/14_distill.py --assets furball --colours brown --models kajiya-kay
    # the recovery (docs/physically_based.md §3): only the pigments, β_m and κ fitted
    python experiments/14_distill.py --assets furball,ponytail \
        --models marschner-dual-pigments,marschner-pigments
    # which part of the light is missing: references of direct light only (§3)
    python experiments/14_distill.py --assets furball,ponytail --max-depth 2 \
        --models marschner,marschner-pigments

Writes DIR/distill.csv (one row per fit), DIR/distill.md (the tables), DIR/fits.json
(`FitResult.to_json()` per fit) and DIR/figures/*.png (target | fit | residual for each
model, `FIGURES`); `--docs DOCS` also copies the figures to DOCS/figures/ and the CSV to
DOCS/distill.csv. Prints a line per fit and the tables.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import shutil
import sys
import time
from pathlib import Path

import numpy as np

import hairjax as hj

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "experiments" / "scenes"

# Pigment concentrations (eumelanin, pheomelanin), d'Eon et al. 2011's units as Mitsuba's.
COLOURS = {"blonde": (0.3, 0.0), "brown": (1.3, 0.2), "black": (8.0, 0.0), "red": (0.1, 1.2)}
ROUGHNESSES = (0.2, 0.4)
AZIMUTHAL_ROUGHNESS = 0.3
ASSETS = ("furball", "ponytail", "sintel")

# The fitted names. A name every model fits goes into SHARED_NAMES (the strand opacity
# `alpha` once hj.fit takes it: that one edit adds it to every fit and every table).
SHARED_NAMES = ("kappa",)
KAJIYA_KAY_NAMES = ("kd", "ks", "shininess", *SHARED_NAMES)
SCHEUERMANN_NAMES = (
    "kd",
    "primary_color",
    "primary_exponent",
    "primary_shift",
    "secondary_color",
    "secondary_exponent",
    "secondary_shift",
    *SHARED_NAMES,
)
# Marschner (docs/model.md §19): the lobe weights are gains the model declares grey (in RGB
# they would take the colour from the melanin, which is what the fit is to find).
MARSCHNER_WEIGHTS = ("weight_r", "weight_tt", "weight_trt")
MARSCHNER_NAMES = (
    *MARSCHNER_WEIGHTS,
    "eumelanin",
    "pheomelanin",
    "longitudinal_roughness",
    "tilt",
    *SHARED_NAMES,
)
# The recovery fits (docs/physically_based.md §3): only the reference's own hair parameters
# are free (and κ, the opacity maps' density, which has no counterpart in the fibres); the
# lobe weights stay at their physical 1 and the tilt at the reference's 2°, so the
# brightness and the colour must come from the pigments and β_m.
PIGMENT_NAMES = ("eumelanin", "pheomelanin", "longitudinal_roughness", *SHARED_NAMES)
FIT_NAMES = {
    "kajiya-kay": KAJIYA_KAY_NAMES,
    "kajiya-kay-mirror": KAJIYA_KAY_NAMES,
    "scheuermann": SCHEUERMANN_NAMES,
    "marschner": MARSCHNER_NAMES,
    "marschner-dual": MARSCHNER_NAMES,
    "marschner-pigments": PIGMENT_NAMES,
    "marschner-dual-pigments": PIGMENT_NAMES,
}

# The sweep's models by default; the pigment-only fits are asked for by name (`--models`).
MODELS = tuple(m for m in FIT_NAMES if not m.endswith("-pigments"))
SHORT = {
    "kajiya-kay": "KK",
    "kajiya-kay-mirror": "KK mirror",
    "scheuermann": "Scheuermann",
    "marschner": "Marschner",
    "marschner-dual": "Marschner dual",
    "marschner-pigments": "Marschner pigments",
    "marschner-dual-pigments": "Marschner dual pigments",
}
# Where every fit starts (ambient 0: the reference has no ambient light).
STARTS = {
    "kajiya-kay": dict(kd=0.3, ks=0.1, shininess=30.0, kappa=1.0, ambient=0.0),
    "kajiya-kay-mirror": dict(kd=0.3, ks=0.1, shininess=30.0, kappa=1.0, ambient=0.0),
    "scheuermann": dict(
        kd=0.3,
        primary_color=0.1,
        primary_exponent=80.0,
        primary_shift=0.1,
        secondary_color=0.1,
        secondary_exponent=20.0,
        secondary_shift=-0.1,
        kappa=1.0,
        ambient=0.0,
    ),
    # A mid brown, Mitsuba's default tilt and a middle roughness: far from every target's
    # pigments (0.1–8) and β_m (0.2, 0.4), so a recovery is not the start.
    "marschner": dict(
        eumelanin=1.0,
        pheomelanin=0.3,
        longitudinal_roughness=0.3,
        tilt=2.0,
        weight_r=1.0,
        weight_tt=1.0,
        weight_trt=1.0,
        kappa=1.0,
        ambient=0.0,
    ),
}
# The same start, with dual scattering on, or with only the pigments and β_m fitted.
STARTS.update(
    dict.fromkeys(("marschner-dual", "marschner-pigments", "marschner-dual-pigments"), STARTS["marschner"])
)


# The views are hj.distill's: front, side (the camera turned 60°) and back-lit train;
# held-out (the camera turned −50° under a side light) is held out.
VIEWS = hj.experimental.DISTILL_VIEWS

# (asset, colour, roughness, view): the figures, each target | fit | residual per model.
FIGURES = (
    ("ponytail", "brown", 0.2, "held-out"),
    ("furball", "blonde", 0.4, "back-lit"),
    ("sintel", "black", 0.2, "front"),
    ("furball", "red", 0.2, "side"),
)


def asset_scene(asset: str, size: int, strands: int | None, data: Path):
    """The asset's scene as the real-time side renders it: its camera at `size`², its key
    light, opaque white 1-px strands (at most `strands` of them, every k-th), shading and
    ambient at the start, no ambient term."""
    if asset == "furball":  # under the default scene's camera and light, as experiments/03
        scene = hj.Scene(
            hj.furball(strands or 1000, 16, seed=1),
            camera=hj.Camera(eye=(0.0, 0.3, 4.2), target=(0.0, -0.1, 0.0), fov=40.0),
            light=hj.Light(direction=(-0.6, -0.8, -0.5)),
            background=(0.02, 0.02, 0.03),
            name="furball",
        )
    else:
        tressfx = data / "tressfx"
        if not tressfx.is_dir():
            raise SystemExit(f"{asset} needs the TressFX assets in {tressfx}: pass --data DIR (shared/data)")
        overrides = {
            "hair.source": str(tressfx / ("ponytail_side.tfx" if asset == "ponytail" else "sintel_hair.tfx"))
        }
        if asset == "sintel":
            overrides["occluder.path"] = str(tressfx / "sintel_head.obj")
        scene = hj.load_scene(
            SCENES / ("tressfx_ponytail.toml" if asset == "ponytail" else "sintel.toml"), overrides
        )
    hair = scene.strands
    if strands is not None and asset != "furball" and len(hair.offsets) - 1 > strands:
        keep = np.arange(0, len(hair.offsets) - 1, math.ceil((len(hair.offsets) - 1) / strands))
        points = np.concatenate([hair.points[hair.offsets[i] : hair.offsets[i + 1]] for i in keep])
        lengths = np.diff(hair.offsets)[keep]
        offsets = np.concatenate([[0], np.cumsum(lengths)])
        hair = hj.Strands(points, offsets, 1.0, hair.width[keep], width_units=hair.width_units)
    hair = dataclasses.replace(hair, alpha=np.ones_like(hair.alpha), color=None)
    camera = dataclasses.replace(scene.camera, width=size, height=size)
    return scene.replace(strands=hair, camera=camera, shadows=hj.Shadows("opacity-maps", 32, 2 * size))


def shading_model(model: str):
    start = STARTS[model]
    if model == "scheuermann":
        maps = hj.ScheuermannMaps(shift_noise=0.0, mask_noise=0.0)
        return hj.Scheuermann(hj.ScheuermannParams(**start), maps)
    if model.startswith("marschner"):
        scattering = "dual" if model.startswith("marschner-dual") else "none"
        return hj.Marschner(hj.MarschnerParams(**start), multiple_scattering=scattering)
    kind = hj.KajiyaKayMirror if model == "kajiya-kay-mirror" else hj.KajiyaKay
    return kind(hj.ShadingParams(**start))


def rmse(a, b) -> float:
    """√(Σ (a − b)² / 3N) over the RGB of every pixel, pooled over the pairs (the fit's RMSE)."""
    pairs = list(zip(a, b))
    total = sum(float(np.sum((np.asarray(x)[..., :3] - np.asarray(y)[..., :3]) ** 2)) for x, y in pairs)
    return math.sqrt(total / sum(3 * np.asarray(x)[..., 0].size for x, _ in pairs))


def _fmt(value, error) -> str:
    v = np.atleast_1d(np.asarray(value, float))
    text = " ".join(f"{x:.3g}" for x in v)
    if error is None:
        return f"{text} (undetermined)"
    e = np.atleast_1d(np.asarray(error, float))
    return f"{text} ± {' '.join(f'{x:.2g}' for x in e)}"


def distill_one(args, model: str, base, colour: str, roughness: float, refs) -> tuple[dict, object]:
    """`hj.distill` of `model` on `base`'s views: rendering the references (with their
    second seed, for the noise floor) where `refs` is None. Returns (the CSV row's
    numbers, the Distillation)."""
    eu, pheo = COLOURS[colour]
    shading = shading_model(model)
    rendered = []  # when each reference was finished, for the render time

    def progress(done, total, message):
        if message.startswith("reference"):
            rendered.append(time.perf_counter())

    t0 = time.perf_counter()
    d = hj.distill(
        base.replace(shading=shading),
        shading,
        eumelanin=eu,
        pheomelanin=pheo,
        roughness=roughness,
        azimuthal_roughness=AZIMUTHAL_ROUGHNESS,
        spp=args.spp,
        views=chosen_views(args),
        fit_names=FIT_NAMES[model],
        max_steps=args.max_steps,
        noise_floor=True,
        references=refs,
        progress=progress,
    )
    wall = time.perf_counter() - (rendered[-1] if rendered else t0)
    r, train = d.result, [v.name for v in d.views if v.train]
    start = shading.params
    started = [np.asarray(hj.render(d.scenes[v].replace(params=start))) for v in train]
    row = dict(
        model=model,
        start_rmse=rmse(started, [d.references[v] for v in train]),
        train_rmse=float(r.rmse),
        holdout_rmse=float(r.holdout_rmse),
        floor_train=d.floor(train=True),
        floor_holdout=d.floor(train=False),
        target_rms=rmse([d.references[v] for v in train], [0.0 * d.references[v] for v in train]),
        steps=r.steps,
        time_s=float(r.time_s),
        wall_s=wall,
        render_s=(rendered[-1] - t0) if rendered else 0.0,
        termination=r.termination,
        undetermined=" ".join(r.undetermined),
        params="; ".join(f"{n} {_fmt(r.get(n), r.std_error.get(n))}" for n in FIT_NAMES[model]),
        **{f"fit_{n}": float(np.asarray(r.get(n))) for n in RECOVERED if n in FIT_NAMES[model]},
        **{f"rmse_{v}": e for v, e in d.rmse.items()},
        **{f"floor_{v}": e for v, e in d.floors.items()},
    )
    return row, d


# --- tables and figures ------------------------------------------------------------------


def _ratio(x: float, floor: float) -> str:
    return f"{x:.4f} ({x / floor:.1f}×)" if floor > 0 else f"{x:.4f}"


def summary_table(rows: list[dict], models: list[str]) -> str:
    """One line per (asset, colour, roughness): the floor, then per model its training and
    held-out RMSE, each with its ratio to the floor of the same pixels."""
    head = "| asset | colour | β_m | target RMS | floor train / held-out |"
    head += "".join(f" {SHORT[m]} train | {SHORT[m]} held-out |" for m in models)
    lines = [head, "|---" * (5 + 2 * len(models)) + "|"]
    keys = list(dict.fromkeys((r["asset"], r["colour"], r["roughness"]) for r in rows))
    for key in keys:
        sel = {r["model"]: r for r in rows if (r["asset"], r["colour"], r["roughness"]) == key}
        first = next(iter(sel.values()))
        cells = [
            *map(str, key),
            f"{first['target_rms']:.4f}",
            f"{first['floor_train']:.4f} / {first['floor_holdout']:.4f}",
        ]
        for m in models:
            r = sel.get(m)
            cells += (
                [_ratio(r["train_rmse"], r["floor_train"]), _ratio(r["holdout_rmse"], r["floor_holdout"])]
                if r
                else ["", ""]
            )
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def view_table(rows: list[dict], models: list[str]) -> str:
    """Per model and view, the median over the sweep of the fitted view's RMSE and of its
    ratio to the view's floor, and the same for light (blonde) and dark (black) hair."""
    views = [v for v in VIEWS if any(f"rmse_{v.name}" in r for r in rows)]
    lines = [
        "| model | hair | " + " | ".join(v.name for v in views) + " |",
        "|---" * (2 + len(views)) + "|",
    ]
    for m in models:
        for hair, colours in (("all", tuple(COLOURS)), ("blonde", ("blonde",)), ("black", ("black",))):
            sel = [r for r in rows if r["model"] == m and r["colour"] in colours]
            if not sel:
                continue
            cells = []
            for v in views:
                err = float(np.median([r[f"rmse_{v.name}"] for r in sel]))
                ratio = float(np.median([r[f"rmse_{v.name}"] / r[f"floor_{v.name}"] for r in sel]))
                cells.append(f"{err:.4f} ({ratio:.1f}×)")
            lines.append(f"| {SHORT[m]} | {hair} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


# What a Marschner fit recovers, against the reference's true values (the asset's
# [reference] table: COLOURS' pigments, the β_m of the sweep).
RECOVERED = ("eumelanin", "pheomelanin", "longitudinal_roughness")


def recovery_table(rows: list[dict]) -> str:
    """Per Marschner fit: the true pigments and β_m beside the fitted ones."""
    lines = [
        "| asset | colour | model | eumelanin true / fitted | pheomelanin true / fitted "
        "| β_m true / fitted |",
        "|---" * 6 + "|",
    ]
    for r in rows:
        if not r["model"].startswith("marschner"):
            continue
        eu, pheo = COLOURS[r["colour"]]
        truth = (eu, pheo, r["roughness"])
        cells = [f"{t:g} / {r[f'fit_{n}']:.3g}" for t, n in zip(truth, RECOVERED)]
        lines.append(f"| {r['asset']} | {r['colour']} | {SHORT[r['model']]} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def params_table(rows: list[dict]) -> str:
    lines = [
        "| asset | colour | β_m | model | steps | time | termination | fitted parameters ± standard error |",
        "|---" * 8 + "|",
    ]
    for r in rows:
        lines.append(
            f"| {r['asset']} | {r['colour']} | {r['roughness']} | {SHORT[r['model']]} | {r['steps']} | "
            f"{r['time_s']:.1f} s | {r['termination']} | {r['params']} |"
        )
    return "\n".join(lines)


def _display(image, scale: float) -> np.ndarray:
    """Linear RGB → display: exposed so the target's 99.5th percentile is white, then γ 2.2."""
    return np.clip(np.asarray(image)[..., :3] * scale, 0.0, 1.0) ** (1 / 2.2)


def figure(path: Path, target, fitted: dict, title: str) -> None:
    """target | fit | residual (fit − target, RGB mean, one symmetric scale for every
    model), one row per model."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    rgb = np.asarray(target)[..., :3]
    scale = 1.0 / max(float(np.percentile(rgb, 99.5)), 1e-6)
    diffs = {m: np.mean(np.asarray(f)[..., :3] - rgb, axis=-1) for m, f in fitted.items()}
    limit = max(max(float(np.abs(d).max()) for d in diffs.values()), 1e-12)
    fig = Figure(figsize=(9.5, 3.0 * len(fitted) + 0.5), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(fitted), 3, squeeze=False)
    for row, (m, image) in zip(axes, fitted.items()):
        row[0].imshow(_display(target, scale), interpolation="nearest")
        row[0].set_title("reference (Mitsuba)")
        row[1].imshow(_display(image, scale), interpolation="nearest")
        row[1].set_title(f"{SHORT[m]} fit")
        shown = row[2].imshow(diffs[m], cmap="RdBu_r", vmin=-limit, vmax=limit, interpolation="nearest")
        row[2].set_title(f"fit − reference, RMSE {rmse([image], [target]):.4f}")
        fig.colorbar(shown, ax=row[2], shrink=0.85)
        for ax in row:
            ax.set_axis_off()
    fig.suptitle(title)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, format="png", dpi=80)


# --- the sweep ---------------------------------------------------------------------------

FULL = dict(size=96, spp=256, strands={"furball": 1000, "ponytail": None, "sintel": None})
# The reference's longest path: 16 keeps the light scattered between fibres (docs/reference.md).
DEFAULT_MAX_DEPTH = 16
QUICK = dict(
    size=40,
    spp=16,
    strands={"furball": 120},
    models=("kajiya-kay",),
    max_steps=30,
    views=("front", "back-lit", "held-out"),  # fewer views: fewer programs to compile
)
CSV_COLUMNS = (
    "asset",
    "colour",
    "roughness",
    "model",
    "start_rmse",
    "train_rmse",
    "holdout_rmse",
    "floor_train",
    "floor_holdout",
    "target_rms",
    *(f"rmse_{v.name}" for v in VIEWS),
    *(f"floor_{v.name}" for v in VIEWS),
    "steps",
    "time_s",
    "wall_s",
    "render_s",
    "termination",
    "undetermined",
    "params",
    *(f"fit_{n}" for n in RECOVERED),
)


def _path_length(text: str) -> int:
    """`--max-depth`: an integer ≥ 2 (Mitsuba's `max_depth` 1 shows the light sources only,
    and a directional light is never seen), or argparse's one-line error."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 2:
        raise argparse.ArgumentTypeError(f"must be an integer >= 2, got {text!r}")
    return value


def _choices(text: str, allowed, what: str) -> list:
    items = [type(next(iter(allowed)))(x) for x in text.split(",")]
    unknown = [x for x in items if x not in allowed]
    if unknown:
        raise SystemExit(
            f"unknown {what} {', '.join(map(str, unknown))}; choose from {', '.join(map(str, allowed))}"
        )
    return items


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--assets", default=",".join(ASSETS))
    p.add_argument("--colours", default=",".join(COLOURS))
    p.add_argument("--roughnesses", default=",".join(map(str, ROUGHNESSES)), help="longitudinal β_m")
    p.add_argument("--models", default=",".join(MODELS))
    p.add_argument("--size", type=int, default=FULL["size"], help=f"image SIZE² (default {FULL['size']})")
    p.add_argument(
        "--spp", type=int, default=FULL["spp"], help=f"Mitsuba's samples per pixel ({FULL['spp']})"
    )
    p.add_argument("--strands", type=int, default=None, help="at most this many strands per asset")
    p.add_argument("--max-steps", type=int, default=100)
    p.add_argument(
        "--max-depth",
        type=_path_length,
        default=DEFAULT_MAX_DEPTH,
        help=f"the reference's longest path (default {DEFAULT_MAX_DEPTH}); 2 is direct light only, "
        "one scattering event per path, for separating the light scattered between fibres",
    )
    p.add_argument("--data", type=Path, default=ROOT.parent / "shared" / "data", help="shared/data")
    p.add_argument("--out", type=Path, default=Path("out/distill"))
    p.add_argument(
        "--reuse-references",
        action="store_true",
        help="read the references of an earlier run from OUT/references/ where they exist "
        "(every run writes them there) instead of rendering them again",
    )
    p.add_argument(
        "--docs",
        type=Path,
        default=None,
        help="also copy the figures to DOCS/figures/ and the CSV to DOCS/distill.csv",
    )
    p.add_argument(
        "--quick",
        action="store_true",
        help=f"{QUICK['strands']['furball']} fur-ball strands at {QUICK['size']}², {QUICK['spp']} spp, "
        f"brown, β_m 0.2, {', '.join(QUICK['models'])} only, for the test suite",
    )
    return p


def reference_path(args, asset: str, base, colour: str, roughness: float) -> Path:
    """Where a run writes the references (both seeds) of one target, for `--reuse-references`."""
    n = len(base.strands.offsets) - 1
    depth = "" if args.max_depth == DEFAULT_MAX_DEPTH else f"_depth{args.max_depth}"
    name = f"{asset}-{n}_{colour}_{roughness:g}_{args.size}_{args.spp}{depth}.npz"
    return args.out / "references" / name


def chosen_views(args) -> list:
    return [v for v in VIEWS if not args.quick or v.name in QUICK["views"]]


def run_asset(args, asset: str, strands: int | None, colours, roughnesses, models) -> tuple:
    """Every fit of one asset: (CSV rows, FitResult JSONs, figure paths)."""
    base = asset_scene(asset, args.size, strands, args.data)
    base = base.replace(reference=hj.ReferenceSettings(max_depth=args.max_depth))
    chosen = chosen_views(args)
    print(f"{asset}: {len(base.strands.offsets) - 1} strands, {len(base.strands.points)} points", flush=True)
    rows, fits, figures = [], [], []
    for colour in colours:
        for roughness in roughnesses:
            path = reference_path(args, asset, base, colour, roughness)
            refs = None  # the first model's distillation renders them, unless reused
            if args.reuse_references and path.is_file():
                with np.load(path) as f:
                    refs = {v.name: (f[f"{v.name}_0"], f[f"{v.name}_1"]) for v in chosen}
            images, render_s = {}, 0.0
            for m in models:
                row, d = distill_one(args, m, base, colour, roughness, refs)
                if refs is None:
                    refs = {v: (d.references[v], d.second[v]) for v in d.references}
                    path.parent.mkdir(parents=True, exist_ok=True)
                    np.savez_compressed(path, **{f"{v}_{i}": x[i] for v, x in refs.items() for i in (0, 1)})
                    render_s = row["render_s"]
                row.update(asset=asset, colour=colour, roughness=roughness, render_s=render_s)
                rows.append(row)
                images[m] = d.images
                r = d.result
                fits.append(dict(asset=asset, colour=colour, roughness=roughness, **r.to_json()))
                print(
                    f"  {asset:<8} {colour:<6} {roughness:<4} {SHORT[m]:<11} "
                    f"start {row['start_rmse']:.4f} train {row['train_rmse']:.4f} "
                    f"(floor {row['floor_train']:.4f}) held-out {row['holdout_rmse']:.4f} "
                    f"(floor {row['floor_holdout']:.4f}) {r.steps} steps {row['wall_s']:.1f} s "
                    f"{r.termination}",
                    flush=True,
                )
            for v in chosen:
                if refs is not None and (
                    (asset, colour, roughness, v.name) in FIGURES or (args.quick and not v.train)
                ):
                    path = args.out / "figures" / f"distill_{asset}_{colour}_{roughness:g}_{v.name}.png"
                    title = (
                        f"{asset}, {colour}, β_m {roughness:g}, {v.name} view ({args.size}², {args.spp} spp)"
                    )
                    figure(path, refs[v.name][0], {m: images[m][v.name] for m in models}, title)
                    figures.append(path)
    return rows, fits, figures


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    from hairjax.experimental import write_csv, write_json, write_text

    strands = dict(FULL["strands"])
    if args.quick:
        args.size, args.spp, strands = QUICK["size"], QUICK["spp"], dict(QUICK["strands"])
        args.assets, args.colours, args.roughnesses = "furball", "brown", "0.2"
        args.models, args.max_steps = ",".join(QUICK["models"]), min(args.max_steps, QUICK["max_steps"])
    if args.strands is not None:
        strands = {a: args.strands for a in ASSETS}
    assets = _choices(args.assets, ASSETS, "asset")
    colours = _choices(args.colours, tuple(COLOURS), "colour")
    roughnesses = [float(x) for x in args.roughnesses.split(",")]
    models = _choices(args.models, tuple(FIT_NAMES), "model")
    print(
        f"distill: {', '.join(assets)} × {', '.join(colours)} × β_m {', '.join(map(str, roughnesses))} "
        f"× {', '.join(models)}; {args.size}², {args.spp} spp, {hj.__version__}",
        flush=True,
    )
    started = time.perf_counter()
    rows, fits, figures = [], [], []
    for asset in assets:
        more = run_asset(args, asset, strands.get(asset), colours, roughnesses, models)
        for acc, new in zip((rows, fits, figures), more):
            acc.extend(new)

    total = time.perf_counter() - started
    header = (
        f"{', '.join(assets)}; {args.size}², {args.spp} spp (Mitsuba `max_depth` {args.max_depth}); "
        f"training views {', '.join(v.name for v in chosen_views(args) if v.train)}, held out: "
        f"{', '.join(v.name for v in chosen_views(args) if not v.train)}; total {total:.0f} s"
    )
    text = "\n\n".join(
        [
            header,
            "RMSE (its ratio to the noise floor of the same pixels):",
            summary_table(rows, models),
            "Per view, median over the sweep: the fitted view's RMSE (its ratio to that view's floor):",
            view_table(rows, models),
            "Marschner's pigments and roughness, true (the reference's) against fitted:",
            recovery_table(rows),
            "Every fit:",
            params_table(rows),
        ]
    )
    args.out.mkdir(parents=True, exist_ok=True)
    write_csv(args.out / "distill.csv", CSV_COLUMNS, rows, float_format=".6g")
    write_text(args.out / "distill.md", text + "\n")
    write_json(args.out / "fits.json", fits)
    if args.docs is not None:
        # The fitted parameters per model, colour and roughness with their held-out RMSE,
        # for the people who set them in an engine (docs/physically_based.md §3).
        write_csv(args.docs / "distill.csv", CSV_COLUMNS, rows, float_format=".6g")
        for path in figures:
            (args.docs / "figures").mkdir(parents=True, exist_ok=True)
            shutil.copyfile(path, args.docs / "figures" / path.name)
    print()
    print(text)
    print(f"wrote {args.out / 'distill.csv'}, distill.md, fits.json, {len(figures)} figure(s)")
    print(f"total {total:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
