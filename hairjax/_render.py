"""The staged renderer: scene → geometry stage → shading stage → image (docs/model.md,
docs/architecture.md).

- `_geometry_stage/_setup.prepare(scene)`: the set-up that depends on geometry, camera and light only.
- `geometry_stage(scene, alpha)` (`_geometry_stage/_stage.py`): compositing weights and Ω,
  differentiable in the per-strand `alpha`.
- `shading_stage(geometry, params)` (`_shading/_stage.py`): the model's colours at the
  points and their composite, differentiable in the shading parameters.

Both earlier stages are cached per scene (`_cache`); re-rendering with new parameters
re-runs only the shading stage.
"""

from __future__ import annotations

import time

import jax
from jaxtyping import Array, Float

from ._cache import forget
from ._geometry._capacity import refuses_out_of_memory
from ._geometry._placement import Placement
from ._geometry_stage._estimate import check_capacity
from ._geometry_stage._setup import prepare, render_cutoff
from ._geometry_stage._stage import geometry_stage
from ._progress import Progress
from ._scene._scene import Scene
from ._shading import shading_stage

__all__ = ["render", "render_profiled"]


@refuses_out_of_memory
def render(
    scene: Scene,
    params=None,
    alpha: Float[Array, " S"] | None = None,
    *,
    order=None,
    placement: Placement | None = None,
) -> Float[Array, "H W 4"]:
    """Render `scene` to linear RGBA `[H, W, 4]`.

    Differentiable in `params` (the shading model's parameters, default `scene.params`) and
    in the per-strand `alpha` (default the scene's); jit-able with the scene closed over:
    `jax.jit(lambda p: render(scene, p))` (the geometry then enters the compiled function
    as constants; for repeated calls, `shading_stage(geometry_stage(scene), p)` passes it
    as arguments instead). With the default `alpha`, both earlier stages are cached per
    scene, so a new `params` re-runs only the shading stage. `order`: segment indices to
    draw in, instead of sorting for this camera (e.g. an order reused from an earlier
    view, kim-2003 Fig. 8; see `visibility_order`); the earlier stages then run afresh.
    `placement`: where the set-up's raster and grouping run, "host" (numba loops) or
    "device" (XLA programs on JAX's default device); None takes the default, the device
    unless it is the CPU, or `HAIRJAX_SETUP` (docs/model.md §5).
    """
    params = scene.params if params is None else params
    if scene.patches is not None:  # §18: hair patches, drawn with slide 17's four passes
        if alpha is not None or order is not None:
            raise ValueError("a hair-patch scene takes neither `alpha` nor `order`")
        from ._patches import render_patches  # Lazy: only patch scenes need it

        check_capacity(scene)  # the image, points and maps, before the patches' fragments
        return render_patches(scene, params)
    return shading_stage(geometry_stage(scene, alpha, order=order, placement=placement), params)


@refuses_out_of_memory
def render_profiled(
    scene: Scene, params=None, *, progress: Progress | None = None, placement: Placement | None = None
):
    """Render and time each stage (block-until-ready between stages).

    Returns `(image, timings)`; timings are seconds by stage name, set-up sub-steps
    prefixed with `geometry/`. Includes compilation on a first call. `progress(done,
    total, stage)` (`hairjax._progress`) after each stage, outside the timed spans: three
    (geometry set-up, geometry opacity, shading), one for a hair-patch scene. `placement`:
    as `render`'s.
    """
    params = scene.params if params is None else params
    if scene.patches is not None:  # §18: one stage, the patches' set-up and composite
        t0 = time.perf_counter()
        image = jax.block_until_ready(render(scene, params))
        elapsed = time.perf_counter() - t0
        if progress is not None:
            progress(1, 1, "patches (four passes)")
        return image, {"patches (four passes)": elapsed, "total": elapsed}

    def step(done: int, stage: str) -> float:
        if progress is not None:
            progress(done, 3, stage)
        return time.perf_counter()

    forget(scene)
    t0 = time.perf_counter()
    setup = prepare(scene, placement=placement, cutoff=render_cutoff())
    t1 = time.perf_counter()
    t1p = step(1, "geometry set-up")
    geometry = jax.block_until_ready(geometry_stage(scene, placement=placement))
    t2 = time.perf_counter()
    t2p = step(2, "geometry opacity (JAX)")
    image = jax.block_until_ready(shading_stage(geometry, params))
    t3 = time.perf_counter()
    step(3, "shading")
    timings = {f"geometry/{k}": v for k, v in setup.timings.items()}
    timings["geometry set-up"] = t1 - t0
    timings["geometry opacity (JAX)"] = t2 - t1p
    timings["shading"] = t3 - t2p
    timings["total"] = t3 - t0 - (t1p - t1) - (t2p - t2)  # the stages' sum, without the reports
    return image, timings
