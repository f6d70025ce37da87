"""`hairjax bench`: time the renderer's stages on fur balls (BENCHMARKS.md).

Every configuration runs in a fresh child process (the same interpreter), so that

- its peak resident memory is its own (``ru_maxrss`` of that process, KiB on Linux),
- running out of memory (a ``MemoryError``, or the kernel's OOM killer ending the
  process) is reported in the table and the benchmark goes on with the next one,
- compiled JAX programs and cached set-ups of one configuration do not linger into the
  next.

Each figure is the median of ``--repeats`` runs after one warm-up run that is not
counted (it holds JAX's compilation). One run is `render_profiled(scene)`: the NumPy
set-up (`prepare`, with the scene's cached set-up and geometry cleared first), the JAX
opacity stage (`geometry_stage`) and the shading stage, each waited for with
`jax.block_until_ready`; "full render" is their sum within a run. The shading stage
alone and the gradient of ``sum((image - target)^2)`` with respect to kd, ks, shininess
and kappa are then timed as warm calls on the last run's geometry, and the ordering as
`draw_order(segment_depth(...), "bins", 256)` on the scene's camera depths.

`--backend gl` times the GL renderer instead (`hairjax.gl.render_gl(scene)`: upload, the
opacity-map passes and the camera pass, each waited for with ``glFinish``; "full render"
is the wall time of the call, medians after one warm-up run that compiles the shaders);
`--backend both` times both paths on the same scene in the same child process, GL first,
and prints the ratio JAX full render / GL full render. If no OpenGL context can be
created (`hairjax.gl.GLUnavailable`) the table says "GL unavailable: ..." and the JAX
figures are measured as usual.
"""

from __future__ import annotations

import json
import math
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from .._files import write_json

__all__ = ["bench_main", "configurations", "TARGETS", "STAGES", "GL_PASSES"]

# Scene of the benchmark: the default scene's camera and light (hairjax/scenes/default.toml).
EYE = (0.0, 0.3, 4.2)
TARGET = (0.0, -0.1, 0.0)
FOV = 40.0
POINTS = 16
ORDERING_BINS = 256

# kim-2003 §6: 0.7 M segments/s for the depth-bin ordering on a 700 MHz Pentium III.
KIM_2003_SEGMENTS_PER_S = 0.7e6

TARGETS = {
    "full_render_s": 2.0,            # 100k strands at 1024² (only that configuration)
    "shading_s": 0.100,              # every configuration
    "gradient_over_shading": 3.0,    # every configuration
    "ordering_msegments_per_s": 20.0,  # every configuration
}
FULL_RENDER_TARGET_CONFIG = (100_000, 1024)
# --backend both: the GL full render of FULL_RENDER_TARGET_CONFIG (64 maps) is no slower
# than the JAX path's, i.e. JAX full render / GL full render >= 1.
GL_TARGET_RATIO = 1.0
BACKENDS = ("jax", "gl", "both")
# Sub-timings of `render_gl`, in the order of its passes (GLResult.timings keys).
GL_PASSES = ("upload", "shadows", "camera pass")

# Stage keys of the JSON ("stages"), in table order; set-up sub-steps follow as
# "geometry_setup/<step>" with the step names of `Setup.timings`.
STAGES = ("geometry_setup", "geometry_opacity", "shading", "gradient", "full_render")
STAGE_LABELS = {
    "geometry_setup": "geometry set-up (NumPy)",
    "geometry_opacity": "geometry opacity (JAX)",
    "shading": "shading stage",
    "gradient": "gradient wrt kd, ks, p, kappa",
    "full_render": "full render",
}

QUICK_REPEATS = 2


def configurations(quick: bool) -> list[dict]:
    """The benchmark configurations: fur balls × image sizes (`--quick`: one tiny one)."""
    if quick:
        return [dict(strands=2_000, size=128, maps=8, map_resolution=64)]
    return [dict(strands=n, size=s, maps=64, map_resolution=256)
            for n in (20_000, 100_000) for s in (512, 1024)]


def _config_name(cfg: dict) -> str:
    n = cfg["strands"]
    count = f"{n // 1000}k" if n % 1000 == 0 else str(n)
    return f"{count} @ {cfg['size']}x{cfg['size']}"


# --------------------------------------------------------------------------------------
# The child: one configuration.


def _median(xs):
    return statistics.median(xs) if xs else float("nan")


def _bench_scene(cfg: dict):
    from .._scene import Camera, Light, Ordering, Scene, Shadows
    from .._shading import ShadingParams
    from .._sources import furball

    hair = furball(strands=cfg["strands"], points=POINTS)
    return Scene(
        strands=hair,
        camera=Camera(eye=EYE, target=TARGET, fov=FOV, width=cfg["size"], height=cfg["size"]),
        light=Light(kind="directional", direction=(-0.6, -0.8, -0.5)),
        params=ShadingParams(kd=(0.55, 0.35, 0.2), ks=0.35, shininess=30.0, kappa=1.0,
                             ambient=0.05),
        shadows=Shadows(method="opacity-maps", maps=cfg["maps"],
                        resolution=cfg["map_resolution"]),
        ordering=Ordering(method="bins", bins=ORDERING_BINS),
        background=(0.02, 0.02, 0.03),
        name="bench",
    )


def _measure_gl(scene, repeats: int, progress) -> dict:
    """Time `render_gl(scene)`: one warm-up run (shader compilation), then `repeats`."""
    import numpy as np

    from ..gl import GLUnavailable, get_context, render_gl

    try:
        ctx = get_context()
    except GLUnavailable as err:
        return {"status": "unavailable", "error": f"GL unavailable: {err}"}
    info = {"gl_renderer": ctx.info.get("GL_RENDERER"), "gl_version": ctx.info.get("GL_VERSION")}
    progress("GL warm-up run (compiles the shaders)")
    result = render_gl(scene)
    total: list[float] = []
    passes: dict[str, list[float]] = {}
    for i in range(repeats):
        del result
        progress(f"GL run {i + 1}/{repeats}")
        t0 = time.perf_counter()
        result = render_gl(scene)
        total.append(time.perf_counter() - t0)
        for key, value in result.timings.items():
            passes.setdefault(key, []).append(value)
    return {
        "status": "ok", "error": None, **info,
        "full_render": {"median_s": _median(total), "runs_s": total},
        "passes": {k: {"median_s": _median(v), "runs_s": v} for k, v in passes.items()},
        "image_finite": bool(np.all(np.isfinite(result.image))),
    }


def _measure(cfg: dict, repeats: int, progress) -> dict:
    backend = cfg.get("backend", "jax")
    scene = _bench_scene(cfg)
    out = {}
    if backend in ("gl", "both"):
        try:
            out["gl"] = _measure_gl(scene, repeats, progress)
        except MemoryError:
            raise
        except Exception as err:  # a GL failure is reported; the JAX figures still come
            out["gl"] = {"status": "error", "error": f"GL: {type(err).__name__}: {err}"[:2000]}
        if out["gl"]["status"] == "unavailable":
            progress(out["gl"]["error"])
    if backend == "gl" and out["gl"]["status"] == "ok":
        return out
    out.update(_measure_jax(scene, repeats, progress))
    if out.get("gl", {}).get("status") == "ok":
        out["jax_over_gl"] = (out["stages"]["full_render"]["median_s"]
                              / out["gl"]["full_render"]["median_s"])
    return out


def _measure_jax(scene, repeats: int, progress) -> dict:
    import jax
    import jax.numpy as jnp

    from .._ordering import draw_order, segment_depth
    from .._render import geometry_stage, prepare, render_profiled, shading_stage
    from .._shading import ShadingParams

    params = scene.params

    # One run is `render_profiled`: it clears the scene's cached set-up and geometry, then
    # times prepare, geometry_stage and shading_stage, blocking between them.
    runs: dict[str, list[float]] = {k: [] for k in ("geometry_setup", "geometry_opacity",
                                                    "full_render")}
    substeps: dict[str, list[float]] = {}
    progress("warm-up run (compiles)")
    image, _ = render_profiled(scene)
    for i in range(repeats):
        del image  # so that two runs' arrays never coexist
        progress(f"run {i + 1}/{repeats}")
        image, timings = render_profiled(scene)
        runs["geometry_setup"].append(timings["geometry set-up (NumPy)"])
        runs["geometry_opacity"].append(timings["geometry opacity (JAX)"])
        runs["full_render"].append(timings["total"])
        for key, value in timings.items():
            if key.startswith("geometry/"):
                substeps.setdefault(key.split("/", 1)[1], []).append(value)
    setup = prepare(scene)  # the last run's, cached
    geom = geometry_stage(scene)

    # The shading stage alone, geometry reused: warm calls, as the gradient below. (Its
    # time within a full render, right after a fresh geometry, is noisier.)
    progress("shading stage alone")
    runs["shading"] = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        image = jax.block_until_ready(shading_stage(geom, params))
        runs["shading"].append(time.perf_counter() - t0)

    # Gradient of an image loss with respect to the shading parameters, geometry reused.
    # The geometry is an argument rather than a closed-over constant, so that XLA does not
    # embed tens of millions of fragments in the compiled program.
    target = jax.block_until_ready(shading_stage(
        geom, ShadingParams(kd=(0.4, 0.3, 0.25), ks=0.5, shininess=20.0, kappa=1.5,
                            ambient=params.ambient)))

    def loss(sub, geometry, target_image):
        p = ShadingParams(kd=sub["kd"], ks=sub["ks"], shininess=sub["shininess"],
                          kappa=sub["kappa"], ambient=params.ambient)
        return jnp.sum((shading_stage(geometry, p) - target_image) ** 2)

    grad_fn = jax.jit(jax.grad(loss))
    sub = {"kd": params.kd, "ks": params.ks, "shininess": params.shininess,
           "kappa": params.kappa}
    progress("gradient (compiles, then warm calls)")
    grads = jax.block_until_ready(grad_fn(sub, geom, target))
    runs["gradient"] = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        grads = jax.block_until_ready(grad_fn(sub, geom, target))
        runs["gradient"].append(time.perf_counter() - t0)
    grads_finite = all(bool(jnp.all(jnp.isfinite(g))) for g in jax.tree_util.tree_leaves(grads))

    # Visibility ordering throughput on the scene's camera depths.
    progress("ordering")
    _, depth = setup.view.project(scene.strands.points)
    segments = scene.strands.segments()
    draw_order(segment_depth(depth, segments), "bins", ORDERING_BINS)  # warm-up
    order_runs = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        draw_order(segment_depth(depth, segments), "bins", ORDERING_BINS)
        order_runs.append(time.perf_counter() - t0)
    order_s = _median(order_runs)

    stages = {k: {"median_s": _median(v), "runs_s": v} for k, v in runs.items()}
    for key, values in substeps.items():
        stages[f"geometry_setup/{key}"] = {"median_s": _median(values), "runs_s": values}
    mseg = len(segments) / order_s / 1e6 if order_s > 0 else float("inf")
    return {
        "stages": stages,
        "gradient_over_shading": stages["gradient"]["median_s"] / stages["shading"]["median_s"],
        "gradient_finite": grads_finite,
        "ordering": {
            "method": "bins",
            "bins": ORDERING_BINS,
            "segments": int(len(segments)),
            "median_s": order_s,
            "runs_s": order_runs,
            "msegments_per_s": mseg,
            "speedup_over_kim_2003": mseg * 1e6 / KIM_2003_SEGMENTS_PER_S,
        },
        "points": int(scene.strands.num_points),
        "segments": int(len(segments)),
        "fragments": int(len(setup.frag_pixel)),
        "shadow_fragments": (None if setup.shadow is None
                             else int(len(setup.shadow.frag_coverage))),
        "image_finite": bool(jnp.all(jnp.isfinite(image))),
        "dtype": str(image.dtype),
    }


def _peak_rss_kib() -> int:
    import resource

    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    # ru_maxrss is KiB on Linux and bytes on macOS.
    return int(peak // 1024) if sys.platform == "darwin" else int(peak)


def _child_main(argv) -> int:
    """Entry point of the child process: `<config.json> <result.json>`."""
    cfg_path, out_path = argv
    cfg = json.loads(Path(cfg_path).read_text())
    if cfg.get("x64"):
        import jax

        jax.config.update("jax_enable_x64", True)

    def progress(msg):
        print(f"  {cfg['name']}: {msg}", file=sys.stderr, flush=True)

    result = {"status": "ok", "error": None}
    start = time.perf_counter()
    try:
        result.update(_measure(cfg, cfg["repeats"], progress))
    except MemoryError as err:
        result.update(status="MemoryError", error=f"MemoryError: {err}")
    except Exception as err:  # reported in the table; the parent exits non-zero
        # XLA reports an allocation failure as a RuntimeError "RESOURCE_EXHAUSTED".
        oom = "RESOURCE_EXHAUSTED" in str(err) or "out of memory" in str(err).lower()
        result.update(status="MemoryError" if oom else "error",
                      error=f"{type(err).__name__}: {err}"[:2000])
    import jax

    result["wall_s"] = time.perf_counter() - start
    result["peak_rss_kib"] = _peak_rss_kib()
    result["jax_backend"] = jax.default_backend()
    result["jax_devices"] = [str(d) for d in jax.devices()]
    result["x64"] = bool(jax.config.jax_enable_x64)
    _write_json_atomic(Path(out_path), result)
    return 0


# --------------------------------------------------------------------------------------
# The parent: run the configurations, print the table, write JSON.


def _run_child(cfg: dict, workdir: Path) -> dict:
    cfg_path = workdir / f"config-{cfg['index']}.json"
    out_path = workdir / f"result-{cfg['index']}.json"
    cfg_path.write_text(json.dumps(cfg))
    env = dict(os.environ)
    # The child imports this very package, installed or not.
    package_root = str(Path(__file__).resolve().parents[2])
    env["PYTHONPATH"] = os.pathsep.join(p for p in (package_root, env.get("PYTHONPATH")) if p)
    code = ("import sys; from hairjax.tools._bench import _child_main; "
            "sys.exit(_child_main(sys.argv[1:]))")
    proc = subprocess.run([sys.executable, "-c", code, str(cfg_path), str(out_path)], env=env)
    if proc.returncode == 0 and out_path.exists():
        return json.loads(out_path.read_text())
    if proc.returncode < 0:
        sig = -proc.returncode
        why = "killed by SIGKILL (out of memory?)" if sig == 9 else f"killed by signal {sig}"
        return {"status": "MemoryError" if sig == 9 else "error", "error": why}
    return {"status": "error", "error": f"child process exited with status {proc.returncode}"}


def _machine_info(results: list[dict]) -> dict:
    import jax
    import numpy as np

    backend = next((r.get("jax_backend") for r in results if r.get("jax_backend")), None)
    devices = next((r.get("jax_devices") for r in results if r.get("jax_devices")), None)
    return {
        "platform": platform.platform(),
        "machine": platform.machine(),
        "processor": platform.processor() or None,
        "python": platform.python_version(),
        "cpu_count": os.cpu_count(),
        "cpu_affinity": len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None,
        "numpy_version": np.__version__,
        "jax_version": jax.__version__,
        "jax_backend": backend,
        "jax_devices": devices,
    }


def _targets_met(cfg: dict, r: dict) -> dict:
    if r.get("status") != "ok":
        return {}
    met = {}
    target_config = (cfg["strands"], cfg["size"]) == FULL_RENDER_TARGET_CONFIG
    if target_config and "jax_over_gl" in r:
        met["jax_over_gl"] = r["jax_over_gl"] >= GL_TARGET_RATIO
    if "stages" not in r:
        return met
    met |= {
        "shading_s": r["stages"]["shading"]["median_s"] <= TARGETS["shading_s"],
        "gradient_over_shading":
            r["gradient_over_shading"] <= TARGETS["gradient_over_shading"],
        "ordering_msegments_per_s":
            r["ordering"]["msegments_per_s"] >= TARGETS["ordering_msegments_per_s"],
    }
    if target_config:
        met["full_render_s"] = r["stages"]["full_render"]["median_s"] <= TARGETS["full_render_s"]
    return met


def _fmt_time(s) -> str:
    if s is None or not math.isfinite(s):
        return "-"
    if s < 1.0:
        return f"{s * 1e3:.1f} ms"
    return f"{s:.2f} s"


def _mark(met) -> str:
    return "" if met is None else (" ok" if met else " MISS")


def _format_table(configs: list[dict], results: list[dict], header: str) -> str:
    names = [_config_name(c) for c in configs]
    rows: list[tuple[str, list[str], str]] = []

    def cells(fn):
        out = []
        for cfg, r in zip(configs, results):
            out.append(fn(cfg, r) if r.get("status") == "ok" else "")
        return out

    def stage(key):
        return lambda c, r: _fmt_time(r["stages"].get(key, {}).get("median_s"))

    have_jax = any("stages" in r for r in results)
    have_gl = any("gl" in r for r in results)

    def jax_cells(fn):
        return cells(lambda c, r: fn(c, r) if "stages" in r else "")

    def gl_cells(fn):
        return cells(lambda c, r: fn(c, r) if r.get("gl", {}).get("status") == "ok" else "")

    substeps = []
    for r in results:
        for key in r.get("stages", {}):
            if key.startswith("geometry_setup/") and key not in substeps:
                substeps.append(key)

    if have_jax:
        rows.append((STAGE_LABELS["geometry_setup"], jax_cells(stage("geometry_setup")), ""))
        for key in substeps:
            rows.append(("  " + key.split("/", 1)[1], jax_cells(stage(key)), ""))
        rows.append((STAGE_LABELS["geometry_opacity"], jax_cells(stage("geometry_opacity")), ""))
        rows.append((STAGE_LABELS["shading"],
                     jax_cells(lambda c, r: _fmt_time(r["stages"]["shading"]["median_s"])
                               + _mark(r["targets_met"].get("shading_s"))),
                     f"<= {TARGETS['shading_s'] * 1e3:.0f} ms"))
        rows.append((STAGE_LABELS["gradient"], jax_cells(stage("gradient")), ""))
        rows.append(("  gradient / shading",
                     jax_cells(lambda c, r: f"{r['gradient_over_shading']:.2f}x"
                               + _mark(r["targets_met"].get("gradient_over_shading"))),
                     f"<= {TARGETS['gradient_over_shading']:g}x"))
        rows.append((STAGE_LABELS["full_render"],
                     jax_cells(lambda c, r: _fmt_time(r["stages"]["full_render"]["median_s"])
                               + _mark(r["targets_met"].get("full_render_s"))),
                     f"<= {TARGETS['full_render_s']:g} s at "
                     f"{FULL_RENDER_TARGET_CONFIG[0] // 1000}k @ {FULL_RENDER_TARGET_CONFIG[1]}"))
        rows.append(("ordering (M segments/s)",
                     jax_cells(lambda c, r: f"{r['ordering']['msegments_per_s']:.1f}"
                               + _mark(r["targets_met"].get("ordering_msegments_per_s"))),
                     f">= {TARGETS['ordering_msegments_per_s']:g}"))
        rows.append(("  speed-up over kim-2003",
                     jax_cells(lambda c, r: f"{r['ordering']['speedup_over_kim_2003']:.0f}x"),
                     "(0.7 M/s, P-III 700 MHz)"))
        rows.append(("  segments ordered",
                     jax_cells(lambda c, r: f"{r['ordering']['segments']:,}"), ""))
        rows.append(("camera fragments", jax_cells(lambda c, r: f"{r['fragments']:,}"), ""))
        rows.append(("shadow-map fragments",
                     jax_cells(lambda c, r: "-" if r["shadow_fragments"] is None
                               else f"{r['shadow_fragments']:,}"), ""))
    if have_gl:
        for key in GL_PASSES:
            rows.append((f"GL {key}", gl_cells(
                lambda c, r, key=key: _fmt_time(r["gl"]["passes"].get(key, {}).get("median_s"))),
                ""))
        rows.append(("GL full render",
                     gl_cells(lambda c, r: _fmt_time(r["gl"]["full_render"]["median_s"])), ""))
        if have_jax:
            rows.append(("JAX / GL full render",
                         cells(lambda c, r: f"{r['jax_over_gl']:.2f}x"
                               + _mark(r["targets_met"].get("jax_over_gl"))
                               if "jax_over_gl" in r else ""),
                         f">= {GL_TARGET_RATIO:g}x at {FULL_RENDER_TARGET_CONFIG[0] // 1000}k @ "
                         f"{FULL_RENDER_TARGET_CONFIG[1]}, 64 maps (GL no slower than JAX)"))
        rows.append(("GL status", [r.get("gl", {}).get("status", "-") for r in results], ""))
    rows.append(("peak RSS",
                 [f"{r['peak_rss_kib'] / 1024 ** 2:.2f} GiB" if r.get("peak_rss_kib") else "-"
                  for r in results], ""))
    rows.append(("status", [r.get("status", "?") for r in results], ""))

    head = ("stage", names, "target")
    widths = [max(len(head[0]), *(len(r[0]) for r in rows))]
    for j in range(len(names)):
        widths.append(max(len(names[j]), *(len(r[1][j]) for r in rows)))
    widths.append(max(len(head[2]), *(len(r[2]) for r in rows)))

    def line(label, values, target):
        parts = [label.ljust(widths[0])]
        parts += [v.rjust(w) for v, w in zip(values, widths[1:-1])]
        parts.append(target.ljust(widths[-1]))
        return "  ".join(parts).rstrip()

    out = [header, "", line(*head), "  ".join("-" * w for w in widths)]
    out += [line(*r) for r in rows]
    errors = [(n, r["error"]) for n, r in zip(names, results) if r.get("error")]
    errors += [(n, r["gl"]["error"]) for n, r in zip(names, results)
               if r.get("gl", {}).get("error")]
    if errors:
        out.append("")
        out += [f"{n}: {e}" for n, e in errors]
    return "\n".join(out)


def _finite_or_none(x):
    """JSON has no NaN or infinity: such figures are written as null."""
    if isinstance(x, float) and not math.isfinite(x):
        return None
    if isinstance(x, dict):
        return {k: _finite_or_none(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_finite_or_none(v) for v in x]
    return x


def _write_json_atomic(path: Path, data) -> None:
    """Write JSON atomically; non-finite numbers become null (strict JSON)."""
    write_json(path, _finite_or_none(data), allow_nan=False)


def bench_main(args) -> int:
    """`hairjax bench [--quick] [--repeats N] [--json PATH] [--backend jax|gl|both]`;
    returns the exit status."""
    import jax

    quick = bool(getattr(args, "quick", False))
    backend = getattr(args, "backend", None) or "jax"
    if backend not in BACKENDS:
        raise ValueError(f"--backend must be one of {BACKENDS}, got {backend!r}")
    repeats = int(getattr(args, "repeats", 5))
    if repeats < 1:
        raise ValueError(f"--repeats must be at least 1, got {repeats}")
    if quick:
        repeats = min(repeats, QUICK_REPEATS)
    x64 = bool(jax.config.jax_enable_x64)

    configs = configurations(quick)
    results = []
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="hairjax-bench-") as tmp:
        for i, cfg in enumerate(configs):
            cfg = dict(cfg, index=i, name=_config_name(cfg), repeats=repeats, x64=x64,
                       backend=backend)
            print(f"[{i + 1}/{len(configs)}] {cfg['name']}: {cfg['strands']:,} strands x "
                  f"{POINTS} points, {cfg['maps']} opacity maps of {cfg['map_resolution']}^2",
                  flush=True)
            t0 = time.perf_counter()
            r = _run_child(cfg, Path(tmp))
            r["targets_met"] = _targets_met(cfg, r)
            results.append(r)
            print(f"      {r['status']} in {time.perf_counter() - t0:.1f} s", flush=True)

    machine = _machine_info(results)
    dtype = next((r["dtype"] for r in results if r.get("dtype")), "?")
    gl_info = next((r["gl"] for r in results if r.get("gl", {}).get("status") == "ok"), None)
    if gl_info is not None:
        machine["gl_renderer"] = gl_info.get("gl_renderer")
        machine["gl_version"] = gl_info.get("gl_version")
    gl_line = ""
    if backend != "jax":
        gl_line = ("\nGL: " + (f"{gl_info['gl_renderer']} ({gl_info['gl_version']})"
                               if gl_info else next((r["gl"]["error"] for r in results
                                                     if r.get("gl", {}).get("error")), "-")))
    header = (f"hairjax bench ({backend}): median of {repeats} run(s) after 1 warm-up; "
              f"{machine['platform']}, {machine['cpu_count']} CPUs, "
              f"jax {machine['jax_version']} ({machine['jax_backend']}, {dtype})\n"
              f"scene: fur balls of {POINTS}-point strands, directional light, bins ordering "
              f"({ORDERING_BINS}), camera eye {EYE} target {TARGET} fov {FOV:g}{gl_line}")
    print()
    print(_format_table(configs, results, header))
    print(f"\ntotal {time.perf_counter() - started:.1f} s")

    if getattr(args, "json", None):
        data = {
            "schema": 1,
            "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
            "quick": quick,
            "backend": backend,
            "repeats": repeats,
            "warmup_runs": 1,
            "machine": machine,
            "targets": dict(TARGETS, full_render_config={
                "strands": FULL_RENDER_TARGET_CONFIG[0], "size": FULL_RENDER_TARGET_CONFIG[1]},
                jax_over_gl=GL_TARGET_RATIO),
            "kim_2003_segments_per_s": KIM_2003_SEGMENTS_PER_S,
            "configurations": [
                {"name": _config_name(c), "strands": c["strands"], "points_per_strand": POINTS,
                 "width": c["size"], "height": c["size"], "maps": c["maps"],
                 "map_resolution": c["map_resolution"], "light": "directional",
                 "camera": {"eye": EYE, "target": TARGET, "fov": FOV}, **r}
                for c, r in zip(configs, results)
            ],
        }
        _write_json_atomic(args.json, data)
        print(f"wrote {args.json}")
    # Running out of memory is a property of the machine, not a failure of the benchmark.
    # So is a machine without OpenGL ("unavailable"); a GL error is a failure.
    failed = any(r["status"] not in ("ok", "MemoryError")
                 or r.get("gl", {}).get("status") == "error" for r in results)
    return 1 if failed else 0
