"""The figures of one run on a lent GPU machine: shading, full renders (JAX and GL), the warm
fit and TressFX assets, on whatever JAX device is the default (BENCHMARKS.md).

On JAX's default device (the GPU where there is one, else the CPU) and the GL renderer's
EGL context, this script measures in one process:

- the bench fur ball (`hairjax.tools.bench_scene`, 64 opacity maps of 256²) at 20k strands
  / 512² and 100k / 1024²: the JAX full render as `hairjax bench` times it
  (`render_profiled`: the host set-up with its sub-steps, the opacity stage, the shading
  stage, each waited for), the shading stage alone (warm calls on the last geometry), the
  GL renderer's full render (`hairjax.gl.render_gl`, wall time of the call, with its passes),
  again with its ribbons by vertex pulling instead of the geometry shader, and the fragment
  counts;
- the warm 4-parameter fit (Kd, Ks, shininess, κ) of experiments/02_fit_speed.py's staged
  case (`hairjax.fit`, Levenberg-Marquardt) at 20k / 512²: one cold fit, then the median of
  `--fit-repeats` warm ones;
- AMD's TressFX ponytail (its four parts, `ponytail_*.tfx`, as one head of hair) and bear,
  framed automatically (`frame_camera`, `key_light`, ribbons 1/128 of the bounding radius
  wide, as `hairjax render FILE` frames a file) at 1280 × 720: JAX and GL full renders;
- the machine: `jax.devices()`, versions, the GL renderer's name.

Figures are medians of `--repeats` runs after one warm-up run that is not counted (it holds
compilation). Every section is guarded: an error is recorded in the JSON and the table and
the next section runs; the JSON (`--json`) is rewritten after every section, so a run
stopped early leaves what it measured. Sections that would start after `--budget-s` seconds
are skipped (and say so).

    python experiments/18_device_figures.py --json out/device_figures.json
    python experiments/18_device_figures.py --quick --json /tmp/device_figures.json

Runtime: on the shared 2-core CPU (llvmpipe for GL) `--quick` (2k and 4k strands at 128² and
192², TressFX at 320 × 180) about 30 s; `--bench 20000x512 --skip tressfx` (with the fit)
45 s; `--bench 100000x1024 --skip fit --repeats 2` (with TressFX at 1280 × 720) 80 s. The
default sizes took 74 s on a 16-core machine with an H200 (BENCHMARKS.md, "GPU: one NVIDIA
H200"), most of it the set-up at 100k / 1024² and XLA's compilation. On a machine whose default
device is a GPU, each fur ball is timed again with the set-up on the host
(`placement="host"`, docs/model.md §5); `HAIRJAX_SETUP=host` makes the host the default.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import os
import platform
import resource
import statistics
import sys
import time
import traceback
from pathlib import Path

import numpy as np

import hairjax as hj
from hairjax.experimental import write_json
from hairjax.tools import bench_scene, timed_calls

DEFAULT_DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "tressfx"

# experiments/02_fit_speed.py's fit: the same true and starting parameters.
TRUE = hj.ShadingParams(kd=(0.45, 0.3, 0.2), ks=0.35, shininess=60.0, kappa=3.0, ambient=0.05)
START = hj.ShadingParams(kd=0.6, ks=0.2, shininess=30.0, kappa=1.5, ambient=0.05)
FIT_NAMES = ("kd", "ks", "shininess", "kappa")

# Ribbon width of a framed hair file, as a fraction of its bounding radius (what
# `hairjax.scene_for_hair` gives one file).
WIDTH_FRACTION = 1.0 / 128.0

FULL = dict(
    bench=[(20_000, 512), (100_000, 1024)],
    maps=64,
    map_resolution=256,
    fit=(20_000, 512),
    tfx=(1280, 720),
)
QUICK = dict(bench=[(2_000, 128), (4_000, 192)], maps=8, map_resolution=64, fit=(2_000, 128), tfx=(320, 180))

START_TIME = time.perf_counter()


def count(strands: int) -> str:
    """A strand count as the bench names it: 20k, or 300 below a thousand's multiple."""
    return f"{strands // 1000}k" if strands % 1000 == 0 else str(strands)


def progress(msg: str) -> None:
    print(f"[{time.perf_counter() - START_TIME:7.1f}s] {msg}", flush=True)


def median(xs) -> float:
    return statistics.median(xs) if xs else float("nan")


def stat(xs) -> dict:
    return {"median_s": median(xs), "runs_s": list(xs)}


def error_text(err: BaseException) -> str:
    return f"{type(err).__name__}: {err}"[:2000]


def clean(value):
    """JSON-safe: NaN and infinities become None, NumPy scalars plain numbers."""
    if isinstance(value, dict):
        return {str(k): clean(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [clean(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


# --- the machine ---------------------------------------------------------------------------


def mem_available_gib() -> float | None:
    try:
        with open("/proc/meminfo") as meminfo:
            for line in meminfo:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) / 2**20
    except (OSError, ValueError, IndexError):
        return None
    return None


def device_memory() -> dict | None:
    """The default device's memory statistics (peak bytes in use), where JAX has them."""
    import jax

    try:
        stats = jax.devices()[0].memory_stats()
    except Exception:  # not every backend has them
        return None
    if not stats:
        return None
    keys = ("bytes_in_use", "peak_bytes_in_use", "bytes_limit")
    return {k: stats[k] for k in keys if k in stats}


def machine_info() -> dict:
    import importlib.metadata as md

    import jax

    info: dict = {
        "python": platform.python_version(),
        "platform": platform.platform(),
        "cpu_count": os.cpu_count(),
        "cpu_affinity": len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None,
        "mem_available_gib": mem_available_gib(),
        "jax_version": jax.__version__,
        "jax_backend": jax.default_backend(),
        "jax_devices": [str(d) for d in jax.devices()],
        "device_kind": jax.devices()[0].device_kind,
        "x64": bool(jax.config.jax_enable_x64),  # type: ignore[attr-defined]
        "numpy_version": np.__version__,
        "setup_placement": hj.experimental.default_placement(),  # HAIRJAX_SETUP's default, docs/model.md §5
    }
    for name in (
        "jaxlib",
        "numba",
        "equinox",
        "optimistix",
        "lineax",
        "moderngl",
        "glcontext",
        "OpenImageIO",
    ):
        try:
            info[f"{name}_version"] = md.version(name)
        except md.PackageNotFoundError:
            info[f"{name}_version"] = None
    try:
        from hairjax.gl import get_context

        ctx = get_context()
        info["gl"] = {k: ctx.info.get(k) for k in ("GL_VENDOR", "GL_RENDERER", "GL_VERSION")}
    except Exception as err:  # GL failures are recorded, not fatal
        info["gl"] = {"error": error_text(err)}
    return info


# --- timing --------------------------------------------------------------------------------


def time_jax(scene, repeats: int, label: str, placement=None) -> dict:
    """`hairjax bench`'s JAX runs: `render_profiled` (forgets the scene's stages, then times
    the set-up, the opacity stage and the shading stage, blocking between them); one warm-up
    run, then `repeats`; the set-up at `placement` (None: the default)."""
    runs: dict[str, list[float]] = {}

    def after(k, result, _seconds):
        if k:
            _, timings = result
            for key, value in timings.items():
                runs.setdefault(key, []).append(value)
            progress(f"{label}: JAX run {k}/{repeats}: {timings['total']:.3f} s")

    progress(f"{label}: JAX warm-up render (compiles)")
    timed = timed_calls(lambda: hj.render_profiled(scene, placement=placement), repeats, after)
    image, warm_up = timed.last[0], timed.warm_up_s
    # The last run's, cached: a render's set-up leaves the hidden fragments out, on the host
    # exactly and on a device a superset of them (docs/model.md §6), which the geometry
    # stage then cuts to the same fragments on both.
    setup = hj.experimental.prepare(scene, placement=placement, cutoff=hj.experimental.render_cutoff())
    geometry = hj.geometry_stage(scene, placement=placement)
    pixels = scene.camera.width * scene.camera.height
    shadow = getattr(setup, "shadow", None)
    return {
        "warm_up_s": warm_up,
        "full_render": stat(runs.pop("total")),
        "stages": {k: stat(v) for k, v in runs.items()},
        "fragments": int(len(setup.frag_pixel)),
        "drawn_fragments": int(np.sum(np.asarray(geometry.frag_pixel) < pixels)),  # without the padding
        "shadow_fragments": None if shadow is None else int(shadow.fragments),
        "image_finite": bool(np.all(np.isfinite(np.asarray(image)))),
        "dtype": str(image.dtype),
    }


def time_shading(scene, repeats: int, label: str) -> dict:
    """The shading stage alone on the scene's cached geometry: warm calls, as the bench's."""
    geom = hj.geometry_stage(scene)
    params = scene.params
    runs = timed_calls(lambda: hj.shading_stage(geom, params), repeats).runs_s  # compiled by the renders
    progress(f"{label}: shading stage alone {median(runs) * 1e3:.2f} ms")
    return stat(runs)


def time_gl(scene, repeats: int, label: str, ribbons: str = "geometry-shader") -> dict:
    """`render_gl(scene, ribbons=ribbons)`'s wall time: one warm-up run (shader
    compilation), then `repeats`. Any failure is returned as an error, not raised."""
    try:
        from hairjax.gl import render_gl

        passes: dict[str, list[float]] = {}

        def after(k, result, seconds):
            if k:
                for key, value in result.timings.items():
                    passes.setdefault(key, []).append(value)
                progress(f"{label}: GL run {k}/{repeats}: {seconds:.3f} s")

        progress(f"{label}: GL warm-up render, ribbons by {ribbons}")
        timed = timed_calls(lambda: render_gl(scene, ribbons=ribbons), repeats, after)
        result, warm_up, total = timed.last, timed.warm_up_s, timed.runs_s
        return {
            "status": "ok",
            "error": None,
            "warm_up_s": warm_up,
            "full_render": stat(total),
            "passes": {k: stat(v) for k, v in passes.items()},
            "image_finite": bool(np.all(np.isfinite(result.image))),
        }
    except Exception as err:  # a GL failure is recorded; the JAX figures still stand
        progress(f"{label}: GL failed: {error_text(err)}")
        return {"status": "error", "error": error_text(err)}


def ratio(jax_part: dict, gl_part: dict) -> float | None:
    if gl_part.get("status") != "ok" or "full_render" not in jax_part:
        return None
    return jax_part["full_render"]["median_s"] / gl_part["full_render"]["median_s"]


# --- the sections --------------------------------------------------------------------------


def jax_and_gl(out: dict, scene, repeats: int, label: str, save, shading: bool) -> None:
    """The JAX runs (and the shading stage alone), then the GL runs, into `out`; a failure of
    either is recorded there and the other still runs; `save()` after each."""
    try:
        out["jax"] = time_jax(scene, repeats, label)
        if shading:
            out["shading"] = time_shading(scene, repeats, label)
    except Exception as err:  # e.g. the device's memory: recorded, GL still runs
        traceback.print_exc()
        out.setdefault("jax", {})["error"] = error_text(err)
        progress(f"{label}: JAX failed: {error_text(err)}")
    finally:
        hj.experimental.forget(scene)  # frees the set-up and geometry before GL runs
    out["device_memory"] = device_memory()
    save()
    out["gl"] = time_gl(scene, repeats, label)
    out["jax_over_gl"] = ratio(out["jax"], out["gl"])
    save()
    # The ribbons without a geometry shader (hairjax/gl/_ribbons.py): the same image.
    out["gl_vertex_pulling"] = time_gl(scene, repeats, label, "vertex-pulling")
    save()


def bench_case(out: dict, strands: int, size: int, sizes: dict, repeats: int, save, host_too: bool) -> None:
    """One fur ball: JAX (set-up where JAX runs), GL, and with `host_too` on an accelerator
    JAX again with the set-up on the host (`placement="host"`, docs/model.md §5)."""
    label = f"{count(strands)} @ {size}²"
    scene = bench_scene(
        dict(strands=strands, size=size, maps=sizes["maps"], map_resolution=sizes["map_resolution"])
    )
    out.update(strands=strands, size=size, segments=int(len(scene.strands.segments())))
    jax_and_gl(out, scene, repeats, label, save, shading=True)
    if host_too and hj.experimental.default_placement() == "device":
        hj.experimental.forget(scene)  # the device set-up's arrays, before the host's
        out["jax_host_setup"] = time_jax(scene.replace(), repeats, f"{label}, set-up on the host", "host")
        save()


def fit_case(strands: int, size: int, repeats: int) -> dict:
    """experiments/02_fit_speed.py's staged case: the default scene's fur ball, a JAX target."""
    scene = hj.load_scene(hj.default_scene_path())
    scene = scene.replace(
        strands=hj.furball(strands, 16, alpha=0.5),
        camera=dataclasses.replace(scene.camera, width=size, height=size),
    )
    label = f"fit {count(strands)} @ {size}²"
    progress(f"{label}: target render")
    target = np.asarray(hj.render(scene, TRUE))

    def record(r, wall: float) -> dict:
        err = max(
            float(
                np.max(
                    np.abs(np.asarray(getattr(r.params, n)) - np.asarray(getattr(TRUE, n)))
                    / np.abs(np.asarray(getattr(TRUE, n)))
                )
            )
            for n in FIT_NAMES
        )
        return {
            "time_s": r.time_s,
            "wall_s": wall,
            "geometry_s": r.geometry_s,
            "steps": int(r.steps),
            "worst_rel_error": err,
            "termination": str(r.termination),
        }

    fits: list[dict] = []  # the cold fit, then the warm ones

    def after(k, r, seconds):
        fits.append(record(r, seconds))
        if k == 0:
            progress(f"{label}: cold fit {fits[0]['time_s']:.2f} s, {fits[0]['steps']} steps")
        else:
            progress(f"{label}: warm fit {k}/{repeats}: {fits[k]['time_s']:.3f} s, {fits[k]['steps']} steps")

    progress(f"{label}: cold fit (compiles)")
    timed_calls(lambda: hj.fit(scene, target, init=START), repeats, after)  # Levenberg-Marquardt
    cold, warm = fits[0], fits[1:]
    hj.experimental.forget(scene)
    return {
        "strands": strands,
        "size": size,
        "cold": cold,
        "warm": warm,
        "time_s": stat([w["time_s"] for w in warm]),
        "wall_s": stat([w["wall_s"] for w in warm]),
        "steps": [w["steps"] for w in warm],
        "worst_rel_error": max(w["worst_rel_error"] for w in warm),
        "device_memory": device_memory(),
    }


def merged_strands(parts: list) -> hj.Strands:
    """One `Strands` of several files' strands (the ponytail's four parts)."""
    points = np.concatenate([p.points for p in parts])
    counts = np.concatenate([np.diff(p.offsets) for p in parts])
    offsets = np.concatenate([[0], np.cumsum(counts)])
    colors = [p.color for p in parts]
    color = None if any(c is None for c in colors) else np.concatenate(colors)
    return hj.Strands(points, offsets, alpha=1.0, width=1.0, color=color)


def tfx_scene(paths: list[Path], width: int, height: int, name: str):
    """A framed scene of one or more hair files: `scene_for_hair` of the first, its strands
    replaced by all of them, re-framed and re-lit as `scene_for_hair` frames one file."""
    base = hj.scene_for_hair(paths[0], width=width, height=height)
    if len(paths) == 1:
        return base.replace(name=name)
    hair = merged_strands([hj.load_hair(p) for p in paths])
    centre = 0.5 * (hair.points.min(axis=0) + hair.points.max(axis=0))
    radius = float(np.linalg.norm(hair.points - centre, axis=1).max())
    hair = hair.replace(
        alpha=np.full(hair.num_strands, float(np.mean(base.strands.alpha))),
        width=np.full(hair.num_strands, WIDTH_FRACTION * radius),
        width_units="world",
    )
    camera = hj.experimental.frame_camera(hair, width=width, height=height, fov=base.camera.fov)
    return base.replace(strands=hair, camera=camera, light=hj.experimental.key_light(camera), name=name)


def tfx_case(out: dict, name: str, paths: list[Path], width: int, height: int, repeats: int, save) -> None:
    if not paths or not all(p.is_file() for p in paths):
        raise FileNotFoundError(f"{name}: missing {[str(p) for p in paths]} (--data)")
    scene = tfx_scene(paths, width, height, name)
    out.update(
        files=[p.name for p in paths],
        width=width,
        height=height,
        strands=int(scene.strands.num_strands),
        points=int(scene.strands.num_points),
        segments=int(len(scene.strands.segments())),
        shadows=repr(scene.shadows),
    )
    jax_and_gl(out, scene, repeats, f"{name} {width}x{height}", save, shading=False)


# --- the table -----------------------------------------------------------------------------


def fmt(seconds) -> str:
    if seconds is None or not isinstance(seconds, int | float) or not math.isfinite(seconds):
        return "-"
    return f"{seconds * 1e3:8.2f} ms" if seconds < 1 else f"{seconds:8.3f} s "


def get(d, *keys):
    """d[k1][k2]…, or None where a key is missing (a section that failed part-way)."""
    for k in keys:
        if not isinstance(d, dict) or k not in d:
            return None
        d = d[k]
    return d


def table(results: dict) -> str:
    rows: list[tuple[str, str, str, str]] = []

    def add(label, jax_s=None, gl_s=None, note=""):
        rows.append(
            (label, fmt(jax_s) if jax_s is not None else "", fmt(gl_s) if gl_s is not None else "", note)
        )

    def errors(case) -> str:
        found = [f"{k}: {get(case, k, 'error')}" for k in ("jax", "gl") if get(case, k, "error")]
        if "error" in case:
            found.insert(0, str(case["error"]))
        return "; ".join(e[:70] for e in found)

    def full_render(label, case):
        r = case.get("jax_over_gl")
        frags = get(case, "jax", "fragments")
        note = ", ".join(
            x
            for x in (
                f"JAX/GL {r:.2f}x" if r else "",
                f"{frags:,} fragments" if frags else "",
                f"{case['segments']:,} segments" if case.get("segments") else "",
                errors(case),
            )
            if x
        )
        add(
            label,
            get(case, "jax", "full_render", "median_s"),
            get(case, "gl", "full_render", "median_s"),
            note,
        )

    for key, case in results.get("bench", {}).items():
        add(f"fur ball {key}: shading stage", get(case, "shading", "median_s"))
        full_render(f"fur ball {key}: full render", case)
        if "jax_host_setup" in case:
            add("    full render, set-up on the host", get(case, "jax_host_setup", "full_render", "median_s"))
        stages = get(case, "jax", "stages") or {}
        for stage in ("geometry set-up", "geometry opacity (JAX)", "shading"):
            if stage in stages:
                add(f"    {stage}", stages[stage]["median_s"])
            if stage.startswith("geometry set-up"):
                for sub, st in stages.items():
                    if sub.startswith("geometry/"):
                        add(f"      {sub.split('/', 1)[1]}", st["median_s"])
        for name, st in (get(case, "gl", "passes") or {}).items():
            add(f"    GL {name}", None, st["median_s"])
        pulled = get(case, "gl_vertex_pulling", "full_render", "median_s")
        if pulled is not None:
            add("    GL full render, ribbons by vertex pulling", None, pulled)
    fit = results.get("fit")
    if fit:
        if "error" in fit:
            add("warm 4-parameter fit", note=f"error: {fit['error'][:100]}")
        else:
            note = (
                f"steps {fit['steps']}, worst rel. err {fit['worst_rel_error']:.1e}; "
                f"cold {fit['cold']['time_s']:.2f} s"
            )
            add(
                f"warm fit {count(fit['strands'])} @ {fit['size']}² (after geometry)",
                fit["time_s"]["median_s"],
                None,
                note,
            )
            add("    fit call, wall", fit["wall_s"]["median_s"])
    for key, case in results.get("tressfx", {}).items():
        full_render(f"{key} {case.get('width')}x{case.get('height')}: full render", case)
    header = ("case", "JAX", "GL", "note")
    widths = [max(len(r[i]) for r in [*rows, header]) for i in range(4)]
    lines = [f"{'case':<{widths[0]}}  {'JAX':>{widths[1]}}  {'GL':>{widths[2]}}  note"]
    lines.append("-" * (sum(widths) + 6))
    lines += [f"{a:<{widths[0]}}  {b:>{widths[1]}}  {c:>{widths[2]}}  {d}" for a, b, c, d in rows]
    return "\n".join(lines)


# --- main ----------------------------------------------------------------------------------


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument(
        "--json", type=Path, default=Path("out/device_figures.json"), help="where to write the figures"
    )
    p.add_argument("--data", type=Path, default=DEFAULT_DATA, help="folder of the TressFX files")
    p.add_argument("--repeats", type=int, default=5, help="timed runs after one warm-up")
    p.add_argument("--fit-repeats", type=int, default=3, help="warm fits after one cold one")
    p.add_argument("--quick", action="store_true", help="tiny sizes, for a smoke test")
    p.add_argument("--budget-s", type=float, default=240.0, help="skip sections that would start later")
    p.add_argument(
        "--xla-cache",
        default=os.environ.get("HAIRJAX_CACHE_DIR", str(Path.home() / ".cache" / "hairjax" / "xla")),
        help="JAX's compilation cache folder, shared with the hairjax command ('' for none)",
    )
    p.add_argument(
        "--skip",
        default="",
        help="comma-separated sections to skip: bench,fit,tressfx; host-setup: on an accelerator, "
        "the fur balls' second JAX timing with the set-up on the host",
    )
    p.add_argument(
        "--bench",
        default=None,
        help="fur-ball cases STRANDSxSIZE, comma-separated (default 20000x512,100000x1024)",
    )
    args = p.parse_args(argv)
    sizes = QUICK if args.quick else FULL
    skip = {s.strip() for s in args.skip.split(",") if s.strip()}
    if args.bench:
        cases = [tuple(int(v) for v in c.lower().split("x")) for c in args.bench.split(",") if c.strip()]
        sizes = dict(sizes, bench=cases)

    import jax

    if args.xla_cache:
        jax.config.update("jax_compilation_cache_dir", args.xla_cache)
        jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.2)

    results: dict = {"status": "running", "quick": args.quick, "repeats": args.repeats, "errors": []}

    def save() -> None:
        results["wall_s"] = time.perf_counter() - START_TIME
        results["peak_rss_gib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20  # KiB on Linux
        write_json(args.json, clean(results))

    def section(name: str, fn) -> None:
        if name in skip:
            results.setdefault("skipped", []).append(f"{name}: --skip")
            return
        elapsed = time.perf_counter() - START_TIME
        if elapsed > args.budget_s:
            results.setdefault("skipped", []).append(
                f"{name}: budget ({elapsed:.0f} s > {args.budget_s:.0f} s)"
            )
            progress(f"skipping {name}: {elapsed:.0f} s past, budget {args.budget_s:.0f} s")
            save()
            return
        progress(f"== {name}")
        try:
            fn()
        except Exception as err:  # recorded; the next section runs
            traceback.print_exc()
            progress(f"{name} failed: {error_text(err)}")
            results["errors"].append(f"{name}: {error_text(err)}")
        save()

    def info() -> None:
        results["machine"] = machine_info()
        m = results["machine"]
        progress(
            f"jax {m['jax_version']} on {m['jax_devices']} ({m['device_kind']}), numpy {m['numpy_version']}"
        )
        progress(f"GL: {m['gl']}")

    section("machine", info)

    def case(part: str, key: str, start: dict, measure) -> None:
        """One case of a section: skipped past the budget; an error recorded, not raised."""
        if time.perf_counter() - START_TIME > args.budget_s:
            results[part][key] = {"error": "skipped: budget"}
            return
        try:
            results[part][key] = start
            measure(results[part][key])
        except Exception as err:
            traceback.print_exc()
            results[part][key] = {"error": error_text(err)}
            results["errors"].append(f"{part} {key}: {error_text(err)}")
        save()

    def bench() -> None:
        results["bench"] = {}
        for strands, size in sizes["bench"]:
            case(
                "bench",
                f"{count(strands)} @ {size}x{size}",
                {},
                lambda out, n=strands, s=size: bench_case(
                    out, n, s, sizes, args.repeats, save, "host-setup" not in skip
                ),
            )

    section("bench", bench)

    def fit() -> None:
        strands, size = sizes["fit"]
        results["fit"] = {"error": "running"}
        try:
            results["fit"] = fit_case(strands, size, args.fit_repeats)
        except Exception as err:
            results["fit"] = {"error": error_text(err)}
            raise

    section("fit", fit)

    def tressfx() -> None:
        width, height = sizes["tfx"]
        results["tressfx"] = {}
        assets = {
            "ponytail": sorted(args.data.glob("ponytail_*.tfx")),
            "bear": [args.data / "bear.tfx"],
        }
        for name, paths in assets.items():
            case(
                "tressfx",
                name,
                {"width": width, "height": height},
                lambda out, n=name, p=paths: tfx_case(out, n, p, width, height, args.repeats, save),
            )

    section("tressfx", tressfx)

    results["status"] = "done" if not results["errors"] else "done with errors"
    save()
    m = results.get("machine", {})
    print()
    print(
        f"device figures: median of {args.repeats} run(s) after 1 warm-up; jax {m.get('jax_version')} on "
        f"{m.get('jax_devices')}; GL: {m.get('gl', {}).get('GL_RENDERER', m.get('gl'))}; "
        f"{m.get('cpu_count')} CPUs; total {results['wall_s']:.0f} s"
    )
    print(table(results))
    for e in results["errors"]:
        print(f"error: {e}")
    print(f"wrote {args.json}", flush=True)
    return 0 if not results["errors"] else 1


if __name__ == "__main__":
    sys.exit(main())
