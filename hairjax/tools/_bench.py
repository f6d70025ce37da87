"""`hairjax bench`: time the renderer's stages on fur balls (BENCHMARKS.md).

Every configuration runs in a fresh child process (the same interpreter), so that

- its peak resident memory is its own (``ru_maxrss`` of that process, KiB on Linux),
- running out of memory (a ``MemoryError``, or the kernel's OOM killer ending the
  process) is reported in the table and the benchmark goes on with the next one,
- compiled JAX programs and cached set-ups of one configuration do not linger into the
  next.

The configurations and targets are in `_bench_cases.py`, what the child measures in
`_bench_timing.py`, the table and the JSON in `_bench_report.py`. After them, the cost of
each shading model and quality setting on the first configuration, in a child process of
its own (`_bench_models.py`): a second table, and the JSON's "shading_models".
"""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from ._bench_cases import (
    BACKENDS,
    EYE,
    FOV,
    FULL_RENDER_TARGET_CONFIG,
    GL_TARGET_RATIO,
    JAX_TARGET_CONFIGS,
    JAX_TARGET_RATIO,
    KIM_2003_SEGMENTS_PER_S,
    ORDERING_BINS,
    PEAK_RSS_TARGET_GIB,
    POINTS,
    QUICK_REPEATS,
    TARGET,
    TARGETS,
    config_name,
    configurations,
)
from ._bench_models import format_models_table, model_names
from ._bench_report import format_table, missed_targets, verdict, verdict_line, write_json_strict

__all__ = ["bench_main"]


def _run_child(cfg: dict, workdir: Path, entry: tuple[str, str] = ("_bench_timing", "child_main")) -> dict:
    """Run `hairjax.tools.<module>.<function>` (`entry`) on `cfg` in a child process."""
    cfg_path = workdir / f"config-{cfg['index']}.json"
    out_path = workdir / f"result-{cfg['index']}.json"
    cfg_path.write_text(json.dumps(cfg))
    env = dict(os.environ)
    # The child imports this very package, installed or not.
    package_root = str(Path(__file__).resolve().parents[2])
    env["PYTHONPATH"] = os.pathsep.join(p for p in (package_root, env.get("PYTHONPATH")) if p)
    module, function = entry
    code = f"import sys; from hairjax.tools.{module} import {function}; sys.exit({function}(sys.argv[1:]))"
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
    kind = next((r.get("jax_device_kind") for r in results if r.get("jax_device_kind")), None)
    devices = next((r.get("jax_devices") for r in results if r.get("jax_devices")), None)
    placement = next((r.get("setup_placement") for r in results if r.get("setup_placement")), None)
    gl = next((r["gl"] for r in results if r.get("gl", {}).get("status") == "ok"), None)
    renderer = (
        {} if gl is None else {"gl_renderer": gl.get("gl_renderer"), "gl_version": gl.get("gl_version")}
    )
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
        "jax_device_kind": kind,
        "jax_devices": devices,
        "setup_placement": placement,
        **renderer,
    }


def _targets_met(cfg: dict, r: dict) -> dict:
    if r.get("status") != "ok":
        return {}
    met = {}
    target_config = (cfg["strands"], cfg["size"]) == FULL_RENDER_TARGET_CONFIG
    if target_config and "jax_over_gl" in r:
        met["jax_over_gl"] = r["jax_over_gl"] >= GL_TARGET_RATIO
    if (cfg["strands"], cfg["size"]) in JAX_TARGET_CONFIGS and "jax_over_gl" in r:
        met["jax_no_slower_than_gl"] = r["jax_over_gl"] <= JAX_TARGET_RATIO
    if target_config and r.get("peak_rss_kib"):
        met["peak_rss"] = r["peak_rss_kib"] / 1024**2 <= PEAK_RSS_TARGET_GIB
    if "stages" not in r:
        return met
    met |= {
        "shading_s": r["stages"]["shading"]["median_s"] <= TARGETS["shading_s"],
        "gradient_over_shading": r["gradient_over_shading"] <= TARGETS["gradient_over_shading"],
        "ordering_msegments_per_s": r["ordering"]["msegments_per_s"] >= TARGETS["ordering_msegments_per_s"],
    }
    if target_config:
        met["full_render_s"] = r["stages"]["full_render"]["median_s"] <= TARGETS["full_render_s"]
    return met


def _header(backend: str, repeats: int, machine: dict, results: list[dict]) -> str:
    """The table's header: the machine, JAX's build and device (its kind, e.g. an NVIDIA
    card's name, and where the set-up ran) and, where GL was measured, its renderer string."""
    dtype = next((r["dtype"] for r in results if r.get("dtype")), "?")
    gl_line = ""
    if backend != "jax":
        gl_line = "\nGL: " + (
            f"{machine['gl_renderer']} ({machine['gl_version']})"
            if "gl_renderer" in machine
            else next((r["gl"]["error"] for r in results if r.get("gl", {}).get("error")), "-")
        )
    devices = machine["jax_devices"] or []
    return (
        f"hairjax bench ({backend}): median of {repeats} run(s) after 1 warm-up; "
        f"{machine['platform']}, {machine['cpu_count']} CPUs, "
        f"jax {machine['jax_version']} ({machine['jax_backend']}, {dtype}) on "
        f"{len(devices)} x {machine['jax_device_kind']}, "
        f"set-up on the {machine['setup_placement'] or 'host'}\n"
        f"scene: fur balls of {POINTS}-point strands, directional light, bins ordering "
        f"({ORDERING_BINS}), camera eye {EYE} target {TARGET} fov {FOV:g}{gl_line}"
    )


def _json_data(configs, results, machine: dict, quick: bool, backend: str, repeats: int) -> dict:
    """The --json record: the run, the machine, the targets and every configuration's figures."""
    return {
        "schema": 1,
        "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "quick": quick,
        "targets_judged": not quick,
        "targets_missed": [
            {"configuration": config_name(c), "target": key}
            for c, r in zip(configs, results)
            for key in missed_targets(r)
        ],
        "backend": backend,
        "repeats": repeats,
        "warmup_runs": 1,
        "machine": machine,
        "targets": dict(
            TARGETS,
            full_render_config={
                "strands": FULL_RENDER_TARGET_CONFIG[0],
                "size": FULL_RENDER_TARGET_CONFIG[1],
            },
            jax_over_gl=GL_TARGET_RATIO,
            jax_no_slower_than_gl=JAX_TARGET_RATIO,
            jax_no_slower_than_gl_configs=[list(c) for c in JAX_TARGET_CONFIGS],
            peak_rss_gib=PEAK_RSS_TARGET_GIB,
        ),
        "kim_2003_segments_per_s": KIM_2003_SEGMENTS_PER_S,
        "configurations": [
            {
                "name": config_name(c),
                "strands": c["strands"],
                "points_per_strand": POINTS,
                "width": c["size"],
                "height": c["size"],
                "maps": c["maps"],
                "map_resolution": c["map_resolution"],
                "light": "directional",
                "camera": {"eye": EYE, "target": TARGET, "fov": FOV},
                **r,
            }
            for c, r in zip(configs, results)
        ],
    }


def _model_costs(cfg: dict, workdir: Path) -> dict:
    """The cost per shading model on `cfg` (the run's first configuration), in a child
    process of its own (`_bench_models.py`), as the JSON's "shading_models" record."""
    cfg = dict(cfg, index="models", name=config_name(cfg))
    print(f"[models] {cfg['name']}: each shading model and its quality settings", flush=True)
    t0 = time.perf_counter()
    r = _run_child(cfg, workdir, entry=("_bench_models", "models_child_main"))
    print(f"      {r['status']} in {time.perf_counter() - t0:.1f} s", flush=True)
    keep = ("status", "error", "models", "wall_s", "peak_rss_kib")
    return {
        "configuration": cfg["name"],
        "strands": cfg["strands"],
        "width": cfg["size"],
        "height": cfg["size"],
        "maps": cfg["maps"],
        "map_resolution": cfg["map_resolution"],
        **{k: r[k] for k in keep if k in r},
    }


def _models_title(record: dict, repeats: int) -> str:
    return (
        f"shading models: cost per model at {record['configuration']} (the machine of the header "
        f"above; medians of {repeats} warm call(s) after 1 that compiles, geometry reused)"
    )


def bench_main(args) -> int:
    """`hairjax bench [--quick] [--repeats N] [--json PATH] [--backend jax|gl|both]
    [--models NAMES]`; returns the exit status."""
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
    models_run = model_names(getattr(args, "models", None))
    x64 = bool(jax.config.jax_enable_x64)  # type: ignore[attr-defined]  # jax declares its options at run time

    configs = configurations(quick)
    results = []
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="hairjax-bench-") as tmp:
        for i, cfg in enumerate(configs):
            cfg = dict(cfg, index=i, name=config_name(cfg), repeats=repeats, x64=x64, backend=backend)
            print(
                f"[{i + 1}/{len(configs)}] {cfg['name']}: {cfg['strands']:,} strands x "
                f"{POINTS} points, {cfg['maps']} opacity maps of {cfg['map_resolution']}^2",
                flush=True,
            )
            t0 = time.perf_counter()
            r = _run_child(cfg, Path(tmp))
            # --quick's small configuration is not judged against the full ones' targets.
            r["targets_met"] = {} if quick else _targets_met(cfg, r)
            r["verdict"] = verdict(r, judged=not quick)
            results.append(r)
            print(f"      {r['verdict']} in {time.perf_counter() - t0:.1f} s", flush=True)
        base = dict(configs[0], repeats=repeats, x64=x64, backend=backend, models=list(models_run))
        models = _model_costs(base, Path(tmp))

    machine = _machine_info(results)
    header = _header(backend, repeats, machine, results)
    print()
    print(format_table(configs, results, header))
    print()
    print(verdict_line(configs, results, judged=not quick))
    print()
    print(format_models_table(models, backend, _models_title(models, repeats)))
    print(f"total {time.perf_counter() - started:.1f} s")
    if getattr(args, "json", None):
        data = _json_data(configs, results, machine, quick, backend, repeats)
        write_json_strict(args.json, dict(data, shading_models=models))
        print(f"wrote {args.json}")
    # Running out of memory is a property of the machine, not a failure of the benchmark.
    # So is a machine without OpenGL ("unavailable"); a GL error is a failure. So are missed
    # targets: measured, and said in the status row and the line under the table.
    failed = any(
        r.get("status", "ok") not in ("ok", "MemoryError") or r.get("gl", {}).get("status") == "error"
        for r in [*results, models, *models.get("models", [])]
    )
    return 1 if failed else 0
