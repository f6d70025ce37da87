"""The child process of `hairjax bench`: one configuration, timed (BENCHMARKS.md).

Each figure is the median of ``--repeats`` runs after one warm-up run that is not
counted (it holds JAX's compilation). One run is `render_profiled(scene)`: the
set-up (`prepare`, with the scene's cached set-up and geometry cleared first), the JAX
opacity stage (`geometry_stage`) and the shading stage, each waited for with
`jax.block_until_ready`; "full render" is their sum within a run. The shading stage
alone and the gradient of ``sum((image - target)^2)`` with respect to kd, ks, shininess
and kappa are then timed as warm calls on the last run's geometry, and the ordering as
`draw_order(segment_depth(...), Ordering("bins", bins=256))` on the scene's camera depths.

`--backend gl` times the GL renderer instead (`hairjax.gl.render_gl(scene)`: upload, the
opacity-map passes and the camera pass, each waited for with ``glFinish``; "full render"
is the wall time of the call, medians after one warm-up run that compiles the shaders);
`--backend both` times both paths on the same scene in the same child process, GL first,
and prints the ratio JAX full render / GL full render. If no OpenGL context can be
created (`hairjax.gl.GLUnavailable`) the table says "GL unavailable: ..." and the JAX
figures are measured as usual.
"""

from __future__ import annotations

import dataclasses
import json
import statistics
import sys
import time
from pathlib import Path
from typing import Any

from ._bench_cases import KIM_2003_SEGMENTS_PER_S, ORDERING_BINS, bench_scene
from ._bench_report import write_json_strict
from ._compare import TimedCalls, timed_calls

__all__ = ["child_main", "measure_gl"]


def _median(xs):
    return statistics.median(xs) if xs else float("nan")


def measure_gl(scene, repeats: int, progress) -> dict:
    """Time `render_gl(scene)`: one warm-up run (shader compilation), then `repeats`."""
    import numpy as np

    from ..gl import GLUnavailable, render_gl, renderer_info
    from ..gl._work import counted_gl_work

    try:
        info = renderer_info()  # the driver's strings, as render's sidecar records them
    except GLUnavailable as err:
        return {"status": "unavailable", "error": f"GL unavailable: {err}"}
    passes: dict[str, list[float]] = {}

    def after(k, result, _seconds):
        if k:
            for key, value in result.timings.items():
                passes.setdefault(key, []).append(value)
        if k < repeats:
            progress(f"GL run {k + 1}/{repeats}")

    works = []

    def counted():
        with counted_gl_work() as work:
            result = render_gl(scene)
        works.append(work)
        return result

    progress("GL warm-up run (compiles the shaders)")
    timed = timed_calls(counted, repeats, after)
    total = timed.runs_s
    return {
        "status": "ok",
        "error": None,
        **info,
        "full_render": {"median_s": _median(total), "runs_s": total},
        "passes": {k: {"median_s": _median(v), "runs_s": v} for k, v in passes.items()},
        "work": dataclasses.asdict(works[-1]),  # a warm run's (`hairjax/gl/_work.py`)
        "image_finite": bool(np.all(np.isfinite(timed.last.image))),
    }


def _measure(cfg: dict, repeats: int, progress) -> dict:
    backend = cfg.get("backend", "jax")
    scene = bench_scene(cfg)
    out = {}
    if backend in ("gl", "both"):
        try:
            out["gl"] = measure_gl(scene, repeats, progress)
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
        out["paired"] = _measure_pairs(scene, repeats, progress)
        out["jax_over_gl"] = out["paired"]["median_ratio"]
    return out


def _measure_pairs(scene, repeats: int, progress) -> dict:
    """`repeats` pairs of full renders back to back, GL then JAX, and the median of each
    pair's ratio JAX / GL: the two blocks of runs above lie tens of seconds apart at 100k
    strands, and this machine's speed moves by tens of percent within a minute, so a
    ratio of the blocks' medians mixes the renderers with the machine's moods."""
    from .._render import render_profiled
    from ..gl import render_gl

    gl_s, jax_s = [], []
    for i in range(repeats):
        progress(f"pair {i + 1}/{repeats}: GL, then JAX")
        t0 = time.perf_counter()
        result = render_gl(scene)
        gl_s.append(time.perf_counter() - t0)
        del result
        image, timings = render_profiled(scene)
        jax_s.append(timings["total"])
        del image
    ratios = [j / g for j, g in zip(jax_s, gl_s)]
    return {"gl_s": gl_s, "jax_s": jax_s, "ratios": ratios, "median_ratio": _median(ratios)}


def _measure_jax(scene, repeats: int, progress) -> dict:
    from .._geometry_stage._setup import prepare, render_cutoff
    from .._geometry_stage._stage import geometry_stage

    runs, substeps = _time_renders(scene, repeats, progress)
    setup = prepare(scene, cutoff=render_cutoff())  # the last run's, cached
    geom = geometry_stage(scene)
    shading = _time_shading(geom, scene.params, repeats, progress)
    runs["shading"] = shading.runs_s
    gradient = _time_gradient(geom, scene.params, repeats, progress)
    runs["gradient"] = gradient.runs_s
    segments = scene.strands.segments()
    ordering = _time_ordering(scene, setup, segments, repeats, progress)

    stages = {k: {"median_s": _median(v), "runs_s": v} for k, v in runs.items()}
    for key, values in substeps.items():
        stages[f"geometry_setup/{key}"] = {"median_s": _median(values), "runs_s": values}
    image = shading.last
    return {
        "stages": stages,
        "gradient_over_shading": stages["gradient"]["median_s"] / stages["shading"]["median_s"],
        "gradient_finite": _finite(gradient.last),
        "ordering": _ordering_figures(ordering.runs_s, len(segments)),
        "points": int(scene.strands.num_points),
        "segments": int(len(segments)),
        "fragments": int(len(setup.frag_pixel)),
        "shadow_fragments": (None if setup.shadow is None else setup.shadow.fragments),
        "image_finite": _finite(image),
        "dtype": str(image.dtype),
    }


def _time_renders(scene, repeats: int, progress) -> tuple[dict[str, list[float]], dict[str, list[float]]]:
    """One warm-up and `repeats` runs of `render_profiled`: it clears the scene's cached
    set-up and geometry, then times prepare, geometry_stage and shading_stage, blocking
    between them. Returns its figures by stage, and the set-up's sub-steps by name."""
    from .._render import render_profiled

    runs: dict[str, list[float]] = {k: [] for k in ("geometry_setup", "geometry_opacity", "full_render")}
    substeps: dict[str, list[float]] = {}

    def after(k, result, _seconds):
        if k:
            _, timings = result
            runs["geometry_setup"].append(timings["geometry set-up"])
            runs["geometry_opacity"].append(timings["geometry opacity (JAX)"])
            runs["full_render"].append(timings["total"])
            for key, value in timings.items():
                if key.startswith("geometry/"):
                    substeps.setdefault(key.split("/", 1)[1], []).append(value)
        if k < repeats:
            progress(f"run {k + 1}/{repeats}")

    progress("warm-up run (compiles)")
    timed_calls(lambda: render_profiled(scene), repeats, after)
    return runs, substeps


def _time_shading(geom, params, repeats: int, progress) -> TimedCalls:
    """The shading stage alone, geometry reused: warm calls, as the gradient's. (Its time
    within a full render, right after a fresh geometry, is noisier.)"""
    from .._shading import shading_stage

    progress("shading stage alone")
    return timed_calls(lambda: shading_stage(geom, params), repeats)


def _time_gradient(geom, params, repeats: int, progress) -> TimedCalls:
    """The gradient of an image loss with respect to kd, ks, shininess and kappa, geometry
    reused. The geometry is an argument rather than a closed-over constant, so that XLA does
    not embed tens of millions of fragments in the compiled program."""
    import jax
    import jax.numpy as jnp

    from .._shading import ShadingParams, shading_stage

    target = jax.block_until_ready(
        shading_stage(
            geom,
            ShadingParams(kd=(0.4, 0.3, 0.25), ks=0.5, shininess=20.0, kappa=1.5, ambient=params.ambient),
        )
    )

    def loss(sub, geometry, target_image):
        p = ShadingParams(
            kd=sub["kd"], ks=sub["ks"], shininess=sub["shininess"], kappa=sub["kappa"], ambient=params.ambient
        )
        return jnp.sum((shading_stage(geometry, p) - target_image) ** 2)

    grad_fn = jax.jit(jax.grad(loss))
    sub = {"kd": params.kd, "ks": params.ks, "shininess": params.shininess, "kappa": params.kappa}
    progress("gradient (compiles, then warm calls)")
    return timed_calls(lambda: grad_fn(sub, geom, target), repeats)


def _time_ordering(scene, setup, segments, repeats: int, progress) -> TimedCalls:
    """Visibility ordering on the scene's camera depths: `draw_order` with 256 bins."""
    from .._geometry._ordering import Ordering, draw_order, segment_depth

    progress("ordering")
    _, depth = setup.view.project(scene.strands.points)
    return timed_calls(
        lambda: draw_order(segment_depth(depth, segments), Ordering("bins", bins=ORDERING_BINS)), repeats
    )


def _ordering_figures(runs_s: list[float], segments: int) -> dict:
    """The ordering's record: its runs, and its throughput against kim-2003's."""
    order_s = _median(runs_s)
    mseg = segments / order_s / 1e6 if order_s > 0 else float("inf")
    return {
        "method": "bins",
        "bins": ORDERING_BINS,
        "segments": int(segments),
        "median_s": order_s,
        "runs_s": runs_s,
        "msegments_per_s": mseg,
        "speedup_over_kim_2003": mseg * 1e6 / KIM_2003_SEGMENTS_PER_S,
    }


def _finite(tree) -> bool:
    """Whether every leaf of `tree` (JAX arrays) is finite."""
    import jax
    import jax.numpy as jnp

    return all(bool(jnp.all(jnp.isfinite(leaf))) for leaf in jax.tree_util.tree_leaves(tree))


def _peak_rss_kib() -> int:
    import resource

    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    # ru_maxrss is KiB on Linux and bytes on macOS.
    return int(peak // 1024) if sys.platform == "darwin" else int(peak)


def child_main(argv, measure=_measure) -> int:
    """Entry point of the child process: `<config.json> <result.json>`; `measure(cfg,
    repeats, progress)` gives the figures (the stages by default)."""
    cfg_path, out_path = argv
    cfg = json.loads(Path(cfg_path).read_text())
    if cfg.get("x64"):
        import jax

        jax.config.update("jax_enable_x64", True)

    def progress(msg):
        print(f"  {cfg['name']}: {msg}", file=sys.stderr, flush=True)

    result: dict[str, Any] = {"status": "ok", "error": None}
    start = time.perf_counter()
    try:
        result.update(measure(cfg, cfg["repeats"], progress))
    except MemoryError as err:
        result.update(status="MemoryError", error=f"MemoryError: {err}")
    except Exception as err:  # reported in the table; the parent exits non-zero
        # XLA reports an allocation failure as a RuntimeError "RESOURCE_EXHAUSTED".
        oom = "RESOURCE_EXHAUSTED" in str(err) or "out of memory" in str(err).lower()
        result.update(status="MemoryError" if oom else "error", error=f"{type(err).__name__}: {err}"[:2000])
    import jax

    from .._device import device_record

    result["wall_s"] = time.perf_counter() - start
    result["peak_rss_kib"] = _peak_rss_kib()
    device = device_record()
    result["jax_backend"] = device["jax_platform"]
    result["jax_device_kind"] = device["jax_device_kind"]
    result["setup_placement"] = device["setup"]  # docs/model.md §5
    result["jax_devices"] = [str(d) for d in jax.devices()]
    result["x64"] = bool(jax.config.jax_enable_x64)  # type: ignore[attr-defined]  # jax declares its options at run time
    write_json_strict(Path(out_path), result)
    return 0
