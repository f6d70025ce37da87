"""`hairjax bench`'s cost per shading model (BENCHMARKS.md, "Shading models: cost per model").

One configuration (the first of the run: 20k strands @ 512², or `--quick`'s) is rendered
with every registered shading model at its defaults and with the quality settings declared
in `MODEL_VARIANTS`, in one child process of its own. Per model:

- the shading stage alone (geometry reused, warm calls; as the main table's row);
- the gradient of ``sum((image - target)^2)`` with respect to the parameters the model's
  `fittable` names (the fit's cost driver), geometry reused, warm calls;
- with ``--backend gl|both``, the GL frame (`render_gl`, after a warm-up run), or "—" for
  a model whose class has no GL side (`gl_id is None`).

The geometry is computed afresh per model: a model may bring its own per-point inputs
(Scheuermann's), and the set-up is cached per scene object.
"""

from __future__ import annotations

import dataclasses
import math
import statistics

from ._bench_timing import child_main, measure_gl
from ._compare import timed_calls

__all__ = [
    "MODEL_VARIANTS",
    "model_names",
    "model_rows",
    "measure_models",
    "models_child_main",
    "format_models_table",
    "NO_GL",
]

# The quality settings timed besides each registered model's defaults, in one place:
# (model name, static options). A variant naming an option its model's class does not
# declare is left out, so that the list may name options that only some builds have.
MODEL_VARIANTS: tuple[tuple[str, dict], ...] = (
    ("marschner", {"azimuthal": "chiang", "azimuthal_samples": 16}),
    ("marschner", {"azimuthal": "chiang", "azimuthal_samples": 64}),
    ("marschner", {"multiple_scattering": "dual"}),
)
# The GL column of a model without a GL side.
NO_GL = "—"


def _label(name: str, options: dict) -> str:
    if not options:
        return name
    return f"{name} (" + ", ".join(f"{k}={v}" for k, v in options.items()) + ")"


def model_names(text: str | None) -> tuple[str, ...]:
    """The models of `--models` ("a,b"), checked against the registry; None: every one."""
    from .._shading import shading_model_names

    known = shading_model_names()
    if text is None:
        return tuple(known)
    names = tuple(name.strip() for name in text.split(",") if name.strip())
    unknown = [name for name in names if name not in known]
    if not names or unknown:
        raise ValueError(f"--models takes registered shading models ({', '.join(known)}), got {text!r}")
    return names


def model_rows(variants=MODEL_VARIANTS, names: tuple[str, ...] | None = None) -> list[tuple[str, str, dict]]:
    """(label, model name, static options) of every registered model (or of `names`, in
    registry order) at its defaults, each followed by its declared variants (those whose
    options its class declares)."""
    from .._shading import shading_model_class, shading_model_names

    rows: list[tuple[str, str, dict]] = []
    for name in shading_model_names():
        if names is not None and name not in names:
            continue
        fields = {f.name for f in dataclasses.fields(shading_model_class(name))}
        rows.append((name, name, {}))
        for variant_name, options in variants:
            if variant_name == name and set(options) <= fields:
                rows.append((_label(name, options), name, dict(options)))
    return rows


def _median(xs):
    return statistics.median(xs) if xs else float("nan")


def _timed(fn, repeats: int) -> dict:
    """`repeats` warm calls of `fn` (each waited for), after one call that compiles."""
    runs = timed_calls(fn, repeats).runs_s
    return {"median_s": _median(runs), "runs_s": runs}


def _jax_costs(scene, repeats: int, progress) -> dict:
    """The shading stage and the gradient in the model's fittable parameters, warm."""
    import equinox as eqx
    import jax
    import jax.numpy as jnp

    from .._geometry_stage._stage import geometry_stage
    from .._shading import shading_stage

    model, params = scene.shading, scene.params
    progress("geometry")
    geom = geometry_stage(scene)
    progress("shading stage (compiles, then warm calls)")
    shading = _timed(lambda: shading_stage(geom, params), repeats)
    image = shading_stage(geom, params)
    names = [n for n in model.fittable if getattr(params, n, None) is not None]

    def loss(sub, geometry, target_image):
        p = eqx.tree_at(lambda q: [getattr(q, n) for n in names], params, [sub[n] for n in names])
        return jnp.sum((shading_stage(geometry, p) - target_image) ** 2)

    # The geometry is an argument, not a closed-over constant (as the main table's gradient).
    grad_fn = jax.jit(jax.grad(loss))
    sub = {n: getattr(params, n) for n in names}
    target = 0.8 * image  # any image other than the rendered one: the loss's gradient is not 0
    progress("gradient (compiles, then warm calls)")
    gradient = _timed(lambda: grad_fn(sub, geom, target), repeats)
    grads = grad_fn(sub, geom, target)
    return {
        "shading": shading,
        "gradient": gradient,
        "gradient_wrt": names,
        "image_finite": bool(jnp.all(jnp.isfinite(image))),
        "gradient_finite": all(bool(jnp.all(jnp.isfinite(g))) for g in jax.tree_util.tree_leaves(grads)),
    }


def _gl_frame(scene, repeats: int, progress) -> dict:
    if scene.shading.gl_unsupported() is not None:
        return {"status": "no GL side", "error": None}
    try:
        return measure_gl(scene, repeats, progress)
    except MemoryError:
        raise
    except Exception as err:  # a GL failure is reported; the other models still come
        return {"status": "error", "error": f"GL: {type(err).__name__}: {err}"[:2000]}


def measure_models(cfg: dict, repeats: int, progress) -> dict:
    """The cost of every row of `model_rows()` for the models `cfg["models"]` names (every
    registered one unless `--models` said otherwise) on `cfg`'s scene (module docstring)."""
    from .._shading import shading_model_class
    from ._bench_cases import bench_scene

    backend = cfg.get("backend", "jax")
    base = bench_scene(cfg)
    rows = []
    for label, name, options in model_rows(names=tuple(cfg["models"])):
        cls = shading_model_class(name)
        scene = base.replace(shading=cls(**options))

        def tell(msg, label=label):
            progress(f"{label}: {msg}")

        gl_id = None if scene.shading.gl_unsupported() else cls.gl_id  # None: "—" in the table
        row = {"label": label, "model": name, "options": options, "gl_id": gl_id}
        if backend in ("gl", "both"):
            row["gl"] = _gl_frame(scene, repeats, tell)
        if backend in ("jax", "both"):
            row.update(_jax_costs(scene, repeats, tell))
        rows.append(row)
        del scene  # its cached set-up and geometry go with it
    return {"models": rows}


def models_child_main(argv) -> int:
    """Entry point of the child process that measures the cost per model (as `child_main`)."""
    return child_main(argv, measure=measure_models)


def _fmt(s) -> str:
    if s is None or not math.isfinite(s):
        return "-"
    return f"{s * 1e3:.1f} ms" if s < 1.0 else f"{s:.2f} s"


def _row_cells(row: dict, reference_s: float | None, backend: str) -> list[str]:
    cells = [row["label"]]
    if backend in ("jax", "both"):
        shading = row.get("shading", {}).get("median_s")
        gradient = row.get("gradient", {}).get("median_s")
        relative = f"{shading / reference_s:.2f}x" if shading and reference_s else "-"
        over = f"{gradient / shading:.2f}x" if shading and gradient else "-"
        cells += [_fmt(shading), relative, _fmt(gradient), over]
    if backend in ("gl", "both"):
        gl = row.get("gl", {})
        if gl.get("status") == "no GL side":
            cells.append(NO_GL)
        elif gl.get("status") == "ok":
            cells.append(_fmt(gl["full_render"]["median_s"]))
        else:
            cells.append(gl.get("status", "-"))
    return cells


def format_models_table(record: dict, backend: str, title: str) -> str:
    """The printed table of the per-model costs (`record`: `measure_models`'s result with
    the child's status), under `title`."""
    if record.get("status") != "ok":
        return f"{title}\n{record.get('status', '?')}: {record.get('error')}"
    rows = record["models"]
    head = ["model"]
    if backend in ("jax", "both"):
        head += ["shading stage", f"/ {rows[0]['label'] if rows else '-'}", "gradient", "gradient / shading"]
    if backend in ("gl", "both"):
        head.append("GL frame")
    # The shading stage is also given relative to the first row's: the registry's first
    # model (Kajiya-Kay) at its defaults.
    reference = rows[0].get("shading", {}).get("median_s") if rows else None
    table = [head] + [_row_cells(r, reference, backend) for r in rows]
    widths = [max(len(line[j]) for line in table) for j in range(len(head))]

    def line(cells):
        return "  ".join([cells[0].ljust(widths[0])] + [c.rjust(w) for c, w in zip(cells[1:], widths[1:])])

    out = [title, "", line(head), "  ".join("-" * w for w in widths)]
    out += [line(cells) for cells in table[1:]]
    errors = [f"{r['label']}: {r['gl']['error']}" for r in rows if r.get("gl", {}).get("error")]
    return "\n".join(out + ([""] + errors if errors else []))
