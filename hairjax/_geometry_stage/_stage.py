"""The geometry stage (docs/model.md §6, §7): from the set-up and the strands' opacity, the
compositing weights, each pixel's transmittance and alpha, and Ω at every point — JAX,
differentiable in the per-strand opacity. At the scene's own opacities, which nothing
differentiates, the weights on the CPU are the host loop's instead (`host_weights`,
multiplied in order, §6). Its output, `Geometry`, is all the shading stage reads: no
shading parameter enters here.
"""

from __future__ import annotations

from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._cache import cached
from .._composite import pixel_weights
from .._geometry._capacity import refuses_out_of_memory
from .._geometry._hidden import drawn_cutoff, keep_visible
from .._geometry._host import release_heap, to_device
from .._geometry._placement import Placement, placement_of
from .._geometry._weights import host_weights
from .._scene._scene import Scene
from .._shading import AbstractShadingModel
from .._shading._streaks import streak_factors
from ._setup import prepare, render_cutoff

__all__ = ["Geometry", "composite_weights", "fragment_alpha", "geometry_stage"]


class Geometry(eqx.Module):
    """Output of the geometry stage: what the shading stage needs, as JAX arrays.

    `shading` is the scene's shading model (its configuration and, unused by the shading
    stage, its own parameters); `shading_inputs` its per-point inputs (`PointInputs.extra`
    as JAX arrays, or None)."""

    tangent: Float[Array, "P 3"]
    to_light: Float[Array, "P 3"]
    to_eye: Float[Array, "P 3"]
    base_color: Float[Array, "P 3"]
    light_rgb: Float[Array, " 3"]
    omega: Float[Array, " P"] | None
    light_visibility: Float[Array, " P"] | None
    occluder_pixel: Array | None
    occluder_direct: Float[Array, "Q 3"] | None
    occluder_color: Float[Array, " 3"] | None
    occluder_omega: Float[Array, " Q"] | None
    occluder_visibility: Float[Array, " Q"] | None
    frag_pixel: Array
    frag_i0: Array  # the segment's first point; its second is frag_i0 + 1
    frag_t: Float[Array, " F"]
    frag_weight: Float[Array, " F"]
    transmittance: Float[Array, " HW"]
    backdrop: Float[Array, "HW 3"]
    alpha_channel: Float[Array, " HW"]
    shading: AbstractShadingModel
    height: int = eqx.field(static=True)
    width: int = eqx.field(static=True)
    # §16's streak factor per point, None without streaks: the shading package's formula
    # (`streak_factors`), computed once per scene, as it reads no shading parameter;
    # applied by the shading stage (`point_colors`).
    streak: Float[Array, " P"] | None = None
    shading_inputs: Any = None


def fragment_alpha(alpha, strand_of_point, frag_i0, frag_coverage):
    """Each fragment's opacity: its strand's α times its coverage (docs/model.md §5, §6)."""
    return alpha[strand_of_point[frag_i0]] * frag_coverage


@eqx.filter_jit
def composite_weights(
    alpha, strand_of_point, frag_i0, frag_coverage, frag_pixel, opaque, cutoff=0.0, hidden=None
):
    """(weights `[F]`, transmittance `[HW]`, alpha channel `[HW]`, visible `[F]`) of the
    set-up's fragments (sorted by pixel, front to back within a pixel) at the per-strand
    opacities `alpha` (docs/model.md §6). `visible` marks the fragments seen through a
    transmittance of at least `cutoff` (`_hidden`): all of them at 0. A fragment's strand
    (`strand_of_point[frag_i0]`) and its pixel's first and last fragment are derived here
    (`pixel_weights`), not stored with the fragments (BENCHMARKS.md "Memory").
    `hidden` (`[HW]`, optional): the transmittance of fragments the set-up left out
    (`GeometrySetup.hidden`), multiplied into each pixel's."""
    frag_alpha = fragment_alpha(alpha, strand_of_point, frag_i0, frag_coverage)
    weights, transmittance = pixel_weights(frag_alpha, frag_pixel, opaque.shape[0])
    if hidden is not None:
        transmittance = transmittance * hidden
    alpha_channel = 1.0 - transmittance * (1.0 - opaque)
    # w = α·T, so T ≥ c is w ≥ c·α; a fragment with α = 0 counts as seen (it adds 0).
    return weights, transmittance, alpha_channel, weights >= cutoff * frag_alpha


@refuses_out_of_memory
def geometry_stage(
    scene: Scene,
    alpha: Float[Array, " S"] | None = None,
    *,
    order=None,
    cutoff: float | None = None,
    placement: Placement | None = None,
) -> Geometry:
    """Compositing weights and Ω for `scene`, differentiable in the per-strand `alpha`.

    **Arguments:** `scene`; `alpha` (`[S]`, default the scene's strand opacities) — may be
    a traced JAX array, e.g. under `jax.grad`. With the default, the result is computed
    once per scene and cutoff (eagerly, even under a trace) and cached (`_cache`).
    `order`: a draw order to use instead of the scene's (`visibility_order`); then nothing
    is cached. `cutoff`: fragments seen through a transmittance below it are left out
    (`_hidden`, docs/model.md §6); by default `drawn_cutoff` of the working precision,
    where all they would add is below a colour's rounding; 0 keeps every fragment. With
    `alpha` given every fragment is kept: which are hidden depends on α. `placement`: where
    the set-up's raster and grouping run, "host" or "device" (`_placement`; None: the
    default, `HAIRJAX_SETUP`'s); the cache keeps one result per placement.
    """
    where = placement_of(placement)
    if alpha is None:
        cut = drawn_cutoff(jnp.result_type(float)) if cutoff is None else float(cutoff)

        def compute():
            with jax.ensure_compile_time_eval():
                return _geometry_stage(scene, scene.strands.alpha, order, cut, where, concrete=True)

        if order is not None:
            return compute()
        return cached(scene, f"geometry on the {where}, cutoff {cut!r}", compute)
    if cutoff is not None:
        raise ValueError("geometry_stage keeps every fragment when given `alpha`: it takes no `cutoff` then")
    return _geometry_stage(scene, alpha, order, 0.0, where)


def _geometry_stage(
    scene: Scene, alpha, order, cutoff: float, placement: Placement, *, concrete: bool = False
) -> Geometry:
    """The geometry stage, the fragments hidden at `cutoff` left out (none at 0; a
    positive cutoff needs a `concrete` `alpha`: the scene's), its set-up placed at
    `placement`. The weights of a concrete α on the CPU are the host loop's
    (`host_weights`), else JAX's (`composite_weights`)."""
    setup = prepare(scene, order=order, placement=placement, cutoff=render_cutoff(cutoff))
    dtype = jnp.result_type(float)
    alpha = jnp.asarray(alpha, dtype=dtype)
    hw = scene.camera.width * scene.camera.height
    if concrete and all(_on_cpu(x) for x in setup.padded_fragments):
        fragments, transmittance, alpha_channel = _weighed_on_host(setup, alpha, cutoff, dtype)
    else:
        fragments, transmittance, alpha_channel = _weighed_in_jax(setup, alpha, cutoff, dtype, hw)
    omega = occluder_omega = None
    if setup.shadow is not None:
        omega = scene.shadows.omega(setup.shadow, alpha)
        if setup.occluder_pixel is not None:
            # The occluder's surface points follow the strand points (§13).
            p = scene.strands.num_points
            omega, occluder_omega = omega[:p], omega[p:]
    maybe = lambda x, t=dtype: None if x is None else jnp.asarray(x, t)  # noqa: E731
    extra = setup.shading_inputs.extra
    frag_pixel, frag_i0, frag_t, frag_weight = fragments
    return Geometry(
        tangent=jnp.asarray(setup.tangent, dtype),
        to_light=jnp.asarray(setup.to_light, dtype),
        to_eye=jnp.asarray(setup.to_eye, dtype),
        base_color=jnp.asarray(setup.base_color, dtype),
        light_rgb=jnp.asarray(setup.light_rgb, dtype),
        omega=omega,
        light_visibility=maybe(setup.light_visibility),
        occluder_pixel=maybe(setup.occluder_pixel, jnp.int32),
        occluder_direct=maybe(setup.occluder_direct),
        occluder_color=maybe(setup.occluder_color),
        occluder_omega=occluder_omega,
        occluder_visibility=maybe(setup.occluder_visibility),
        frag_pixel=frag_pixel,
        frag_i0=frag_i0,
        frag_t=frag_t,
        frag_weight=frag_weight,
        transmittance=transmittance,
        backdrop=jnp.asarray(setup.backdrop, dtype),
        alpha_channel=alpha_channel,
        shading=scene.shading,
        height=scene.camera.height,
        width=scene.camera.width,
        streak=_streak(scene, setup.strand_of_point, dtype),
        shading_inputs=None if extra is None else jax.tree.map(lambda x: jnp.asarray(x, dtype), extra),
    )


def _on_cpu(x) -> bool:
    """Whether `x`, a set-up's array, lives on the host: NumPy's, or a JAX array on the CPU."""
    return isinstance(x, np.ndarray) or all(d.platform == "cpu" for d in x.devices())


def _weighed_on_host(setup, alpha, cutoff: float, dtype):
    """(fragments (pixel, i0, t, weight), transmittance, alpha channel) of the set-up at
    the concrete `alpha`, by the host loop (`host_weights`), shared with JAX (`_host`)."""
    w = host_weights(
        np.asarray(alpha),
        setup.strand_of_point,
        setup.padded_fragments,
        setup.opaque,
        setup.hidden,
        cutoff,
        dtype,
    )
    fragments = (
        to_device(w.pixel, jnp.int32),
        to_device(w.i0, jnp.int32),
        to_device(w.t, dtype),
        to_device(w.weight, dtype),
    )
    return fragments, jnp.asarray(w.transmittance), jnp.asarray(w.alpha_channel)


def _weighed_in_jax(setup, alpha, cutoff: float, dtype, hw: int):
    """`_weighed_on_host`'s results by JAX (`composite_weights`): differentiable in a
    traced `alpha`, and where the set-up's fragments are on a device."""
    # The fragments padded to their bucket (`fragment_bucket`: pixel H·W, coverage 0, so
    # weight 0), so that the programs below compile once per bucket. Shared with the
    # set-up's aligned arrays where the dtypes agree (`_host`); sent once, for compositing
    # and the Geometry alike (a copy each on a GPU).
    pixel, i0, coverage, t = setup.padded_fragments
    frag_pixel, frag_i0 = to_device(pixel, jnp.int32), to_device(i0, jnp.int32)
    weights, transmittance, alpha_channel, visible = composite_weights(
        alpha,
        jnp.asarray(setup.strand_of_point),
        frag_i0,
        to_device(coverage, dtype),
        frag_pixel,
        jnp.asarray(setup.opaque, dtype),
        jnp.asarray(cutoff, dtype),  # an array, not a static float: one compilation for every cutoff
        None if setup.hidden is None else jnp.asarray(setup.hidden, dtype),
    )
    fragments: tuple[jax.Array, ...] = (frag_pixel, frag_i0, to_device(t, dtype), weights)
    if cutoff > 0 and not bool(jnp.all(visible)):
        # The padding (α = 0: "seen") is cut too, and the kept ones padded to their bucket.
        fragments = keep_visible(visible & (frag_pixel < hw), *fragments, fills=(hw, 0, 0, 0))
    del visible
    release_heap(weights.size * 12)  # compositing's temporaries: α, the scan's runs
    return fragments, transmittance, alpha_channel


def _streak(scene: Scene, strand_of_point, dtype) -> Float[Array, " P"] | None:
    """§16's streak factor of every point (`streak_factors`), None without streaks."""
    if scene.streaks is None:
        return None
    return streak_factors(scene.streaks, strand_of_point, scene.strands.num_strands, dtype)
