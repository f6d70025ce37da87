"""A fit that fits the strands' opacity (docs/fitting.md, "Fitting the strands' opacity"):
the `FitModel` of a shading model whose point is `OpacityParams`, the model's parameters
and one opacity α for every strand.

α reaches the geometry stage (docs/model.md §6, §7): the compositing weights, each pixel's
transmittance, and Ω. So every gain image is recomputed at each step, with the weights
recomputed from the set-up's fragments (`composite_weights`), through plain autodiff; no
fragment is dropped behind low transmittance, since that depends on α. Ω is linear in the
strands' opacities for every shadow method (kim-2003 §4: the maps accumulate α·coverage;
the exact Ω sums it; deep maps' first depths and layers are the geometry's), so
Ω(α) = α·Ω(1), computed once (`tests/fit/test_opacity_fit.py` checks it against the
geometry stage at α for each method).
"""

from __future__ import annotations

import dataclasses
import functools
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._geometry._host import to_device
from .._geometry_stage._setup import prepare
from .._geometry_stage._stage import composite_weights, geometry_stage
from .._scene._scene import Scene
from .._shading import AbstractShadingModel
from .._shading._transforms import LOGIT
from ._model import FitModel
from ._point import ExtendedParams
from ._shading_fit import TargetTerms, fit_model, fixed_image, gain_images_plain, image_of, prepare_terms

__all__ = ["ALPHA", "OpacityParams", "OpacityTerms", "opacity_fit_model", "start_alpha", "strand_alpha"]

# The fit's name of the strands' opacity.
ALPHA = "alpha"


class OpacityParams(ExtendedParams):
    """A model's parameters (`shading`) and one opacity α ∈ (0, 1) for every strand."""

    shading: Any
    alpha: jax.Array  # ()

    def get(self, name: str):
        return self.alpha if name == ALPHA else getattr(self.shading, name)

    def replace(self, values: dict) -> OpacityParams:
        shading = {n: v for n, v in values.items() if n != ALPHA}
        return OpacityParams(dataclasses.replace(self.shading, **shading), values.get(ALPHA, self.alpha))


class OpacityTerms(eqx.Module):
    """One target's terms at the scene's opacity (every gain image varying, no fragment
    dropped) and what recomputes its geometry at another α: the set-up's fragments and
    Ω at α = 1 (`omega_unit`, the strand points' then the occluder's surface points')."""

    terms: TargetTerms
    strand_of_point: jax.Array
    frag_coverage: jax.Array
    opaque: jax.Array
    n_strands: int = eqx.field(static=True)
    omega_unit: jax.Array | None = None
    occluder_omega_unit: jax.Array | None = None

    @property
    def target(self):
        return self.terms.target

    @property
    def sqrt_weight(self):
        return self.terms.sqrt_weight


def start_alpha(scenes) -> float:
    """The fit's start for α: the first scene's strands' mean opacity."""
    return float(np.mean(scenes[0].strands.alpha))


def strand_alpha(scene: Scene, alpha) -> jax.Array:
    """α for every strand of `scene` (`[S]`), as `render`'s `alpha` takes it."""
    return jnp.full(scene.strands.num_strands, alpha, dtype=jnp.result_type(float))


def at_alpha(d: OpacityTerms, alpha) -> TargetTerms:
    """The target's terms with the geometry recomputed at one opacity `alpha` per strand."""
    g = d.terms.geometry
    strand = jnp.full(d.n_strands, alpha, dtype=g.frag_t.dtype)
    weights, transmittance, alpha_channel, _ = composite_weights(
        strand, d.strand_of_point, g.frag_i0, d.frag_coverage, g.frag_pixel, d.opaque
    )
    omega = None if d.omega_unit is None else alpha * d.omega_unit
    occluder_omega = None if d.occluder_omega_unit is None else alpha * d.occluder_omega_unit
    g = dataclasses.replace(
        g,
        frag_weight=weights,
        transmittance=transmittance,
        alpha_channel=alpha_channel,
        omega=omega,
        occluder_omega=occluder_omega,
    )
    return dataclasses.replace(d.terms, geometry=g, constant=transmittance[:, None] * g.backdrop)


def _prepare(gains, scene: Scene, point: OpacityParams, names, target, sqrt_weight) -> OpacityTerms:
    shading_names = tuple(n for n in names if n != ALPHA)
    terms = prepare_terms(gains, scene, point.shading, shading_names, target, sqrt_weight)
    # Every gain's image moves with α: none is fixed, none is composited once. Which
    # fragments α hides moves with it too: every fragment is kept.
    every = geometry_stage(scene, cutoff=0.0)
    terms = dataclasses.replace(terms, geometry=every, fixed={}, bases={}, varying=gains)
    setup = prepare(scene)
    dtype = jnp.result_type(float)
    omega_unit = occluder_omega_unit = None
    if setup.shadow is not None:
        unit = scene.shadows.omega(setup.shadow, jnp.ones(scene.strands.num_strands, dtype))
        p = scene.strands.num_points
        omega_unit = unit[:p]
        occluder_omega_unit = unit[p:] if setup.occluder_pixel is not None else None
    return OpacityTerms(
        terms,
        # As the geometry stage passes them: shared with the set-up where it can (`_host`).
        jnp.asarray(setup.strand_of_point),
        to_device(setup.padded_fragments[2], dtype),  # coverage, padded as the geometry's fragments
        jnp.asarray(setup.opaque, dtype),
        scene.strands.num_strands,
        omega_unit,
        occluder_omega_unit,
    )


@functools.cache
def opacity_fit_model(cls: type[AbstractShadingModel], rgb: tuple[str, ...] = ()) -> FitModel:
    """The fit of shading model class `cls` with the strands' opacity: `fit_model(cls)`'s,
    whose point is `OpacityParams` and whose names include ALPHA (one per class and `rgb`)."""
    base = fit_model(cls, rgb)
    gains = base.linear  # every gain, ambient included

    def images_at(d: OpacityTerms, point: OpacityParams):
        terms = at_alpha(d, point.alpha)
        return terms, gain_images_plain(terms, point.shading)

    def image(d, point):
        terms, found = images_at(d, point)
        return image_of(gains, terms, point.shading, found)

    def images(d, point):
        terms, found = images_at(d, point)
        return fixed_image(terms, point.shading), tuple((n, found[n]) for n in gains)

    return dataclasses.replace(
        base,
        fittable=base.fittable + (ALPHA,),
        transforms={**base.transforms, ALPHA: LOGIT},
        prepare=functools.partial(_prepare, gains),
        image=image,
        gain_images=images,
    )
