"""A fit of any shading model, from the model's own terms (docs/fitting.md, docs/model.md
§6, §8, §13): the `FitModel` of a registered `AbstractShadingModel`.

The model splits its colour by gain (`reflectance`: ambient and lit terms, each linear in
one RGB gain), so a target's image is

    image = Σ_g g ⊙ K_g + T·backdrop + T·O(κ),
    K_g = composite(streak · A_g)               (ambient terms)
    K_g = composite(streak · light · τ · V · L_g)  (lit terms, τ = exp(−κΩ), §7, §13)
          + composite(streak · light · V · S_g)     (scattered terms, §19, if any)

with O(κ) the occluder's colour (§13, `occluder_colors`). The gains are solved for by
variable projection (`_varpro.py`) and the solver iterates on the model's `searched`
parameters. The geometry stage runs once per target; a gain image that no fitted
parameter reaches (`_dependence.py` reads that off the model's jaxpr) is composited once;
the others, and their derivatives in the fitted parameters, in one composite pass per step.
Nothing here is specific to one model: the model is never transcribed a second time.

With the light given (`LightParams`: a fit that fits or holds the light, `_light_fit.py`)
the lit images are those of a white light, the light's colour multiplies them afterwards,
and L is the light's direction; where that direction is fitted, the images it reaches are
recomputed each step through plain autodiff instead of the one-pass rule.
"""

from __future__ import annotations

import functools
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._composite import composite
from .._constants import FIT_TRANSMITTANCE_CUTOFF
from .._geometry_stage._stage import geometry_stage
from .._shading import AbstractShadingModel, occluder_colors, transmittance
from .._shading._light import LightParams, lit_to_light
from .._shading._stage import shading_points
from ._dependence import dependence
from ._model import FitModel
from ._space import SOFTPLUS, with_values

__all__ = [
    "fit_model",
    "TargetTerms",
    "prepare_terms",
    "gain_images",
    "gain_images_plain",
    "target_image",
    "fixed_image",
    "rgb_searched",
]


class TargetTerms(eqx.Module):
    """Per target, everything a step needs that no fitted parameter reaches (`prepare_terms`).

    `geometry`: the geometry stage without the fragments hidden at FIT_TRANSMITTANCE_CUTOFF;
    `ambient_scale`, `light`: what the ambient and the lit terms are multiplied by besides
    τ (the streak factor, §16; and the light's colour); `fixed`: the gain images no fitted
    parameter reaches, at the start's values; `bases`: the per-point terms (A_g or L_g) of
    varying gains that only κ reaches, computed once; `constant`: T·backdrop; `varying`
    (static): the gains whose image is recomputed per step; `searched` (static): the
    fitted searched parameters the custom derivative rule differentiates in; `direction`
    (static): the light's direction is fitted (L comes from the light at every step)."""

    geometry: Any
    ambient_scale: jax.Array
    light: jax.Array
    fixed: dict
    bases: dict
    constant: jax.Array
    target: jax.Array
    sqrt_weight: jax.Array
    varying: tuple[str, ...] = eqx.field(static=True)
    searched: tuple[str, ...] = eqx.field(static=True)
    lit: tuple[str, ...] = eqx.field(static=True, default=())  # the gains of lit terms
    # (gain, fitted searched parameter) pairs where the parameter reaches the gain's term:
    # the derivative images composited; every other pair's is 0 by structure.
    pairs: tuple[tuple[str, str], ...] = eqx.field(static=True, default=())
    direction: bool = eqx.field(static=True, default=False)


def _columns(terms: TargetTerms, params, gains, reflectance=None, light=None) -> jax.Array:
    """The per-point colours of `gains`' images before compositing, `[P, 3·len(gains)]`:
    streak·A_g for an ambient term, streak·light·τ·V·L_g for a lit one. `reflectance`:
    the model's terms at `params`, if known; `light`: L from its direction, if any."""
    g = terms.geometry
    scattered: dict = {}
    if reflectance is None and all(n in terms.bases for n in gains):
        # Only κ moves them: the terms are known.
        lit = {n: b for n, b in terms.bases.items() if n in terms.lit}
        ambient = {n: b for n, b in terms.bases.items() if n not in lit}
    else:
        if reflectance is None:
            reflectance = g.shading.reflectance(shading_points(g, light), params)
        ambient, lit, scattered = reflectance.ambient, reflectance.lit, reflectance.scattered
    lit_scale = visible = terms.light
    if g.omega is not None:
        lit_scale = lit_scale * transmittance(params.kappa, g.omega)[:, None]
    if g.light_visibility is not None:
        lit_scale = lit_scale * g.light_visibility[:, None]
        visible = visible * g.light_visibility[:, None]

    def column(n):
        if n in ambient:
            return ambient[n] * terms.ambient_scale
        # §19: scattered terms are lit without τ (the light came through the hair in front).
        return lit[n] * lit_scale + (scattered[n] * visible if n in scattered else 0.0)

    return jnp.concatenate([column(n) for n in gains], axis=1)


def gain_images_plain(terms: TargetTerms, params, reflectance=None, light=None) -> dict:
    """{gain: its image K_g `[HW, 3]`} at `params` (the fixed ones pass through); `light`:
    L from its direction, if any (`_columns`)."""
    images = dict(terms.fixed)
    if terms.varying:
        stacked = composite(terms.geometry, _columns(terms, params, terms.varying, reflectance, light))
        images.update(zip(terms.varying, jnp.split(stacked, len(terms.varying), axis=1)))
    return images


def _searched_values(terms: TargetTerms, params) -> jax.Array:
    """The fitted searched parameters' values, flat: one entry for a scalar, three for an
    RGB parameter (its channels)."""
    return (
        jnp.concatenate([jnp.ravel(getattr(params, n)) for n in terms.searched])
        if terms.searched
        else jnp.zeros(0, dtype=jnp.result_type(float))
    )


def _offsets(terms: TargetTerms, params) -> list[tuple[str, int, int]]:
    """(name, first entry, entries) of each fitted searched parameter in `_searched_values`."""
    out, i = [], 0
    for n in terms.searched:
        k = int(jnp.size(getattr(params, n)))
        out.append((n, i, k))
        i += k
    return out


def _with_searched(terms: TargetTerms, params, values):
    """`params` with the fitted searched parameters taken from the flat `values`."""
    return with_values(params, {n: values[i : i + k] for n, i, k in _offsets(terms, params)}, ())


@jax.custom_jvp
def _gain_images(terms: TargetTerms, params, values) -> dict:
    return gain_images_plain(terms, _with_searched(terms, params, values))


@_gain_images.defjvp
def _gain_images_jvp(primals, tangents):
    """The images and their derivatives in the fitted searched parameters from one
    composite pass over all the channels. The per-point derivatives come from forward-mode
    autodiff of the model's own terms; the tangent output is a per-pixel linear combination,
    so a Jacobian (vmap over tangent directions) batches only that, not the composites.
    `terms` and `params` are data (the gains do not enter an image): their tangents are
    ignored; the searched parameters enter through `values`."""
    terms, params, values = primals
    _, _, d_values = tangents
    images = dict(terms.fixed)
    d_images = {n: jnp.zeros_like(v) for n, v in terms.fixed.items()}
    if terms.varying:

        def columns(v):
            return _columns(terms, _with_searched(terms, params, v), terms.varying)

        parts = [columns(values)]
        layout = []  # (entry of `values`, gain index) of each derivative block after the values
        if terms.searched:  # ∂(columns)/∂(each entry of the fitted searched parameters), per point
            jac = jax.jacfwd(columns)(values)
            for p, first, size in _offsets(terms, params):
                for j, g in enumerate(terms.varying):
                    if (g, p) in terms.pairs:
                        for i in range(first, first + size):  # an RGB parameter's 3 channels
                            parts.append(jac[:, 3 * j : 3 * j + 3, i])
                            layout.append((i, j))
        stacked = composite(terms.geometry, jnp.concatenate(parts, axis=1))
        k = len(terms.varying)
        values_image, derivatives = stacked[:, : 3 * k], stacked[:, 3 * k :]
        images.update(zip(terms.varying, jnp.split(values_image, k, axis=1)))
        for j, g in enumerate(terms.varying):
            d = jnp.zeros_like(values_image[:, :3])
            for b, (i, jj) in enumerate(layout):
                if jj == j:
                    d = d + derivatives[:, 3 * b : 3 * b + 3] * d_values[i]
            d_images[g] = d
    return images, d_images


def gain_images(terms: TargetTerms, params) -> dict:
    """`gain_images_plain` with the one-pass derivative rule (what a fit step calls)."""
    return _gain_images(terms, params, _searched_values(terms, params))


def fixed_image(terms: TargetTerms, params, light: LightParams | None = None) -> jax.Array:
    """T·backdrop + T·(the occluder's colour at the held ambient and κ, and `light`'s
    colour, `occluder_colors`): the image without the gains' terms."""
    g = terms.geometry
    if g.occluder_pixel is None:
        return terms.constant
    occluder = occluder_colors(g, params, light)
    return terms.constant.at[g.occluder_pixel].add(g.transmittance[g.occluder_pixel][:, None] * occluder)


def image_of(model_gains, terms: TargetTerms, params, images, light: LightParams | None = None) -> jax.Array:
    """fixed_image + Σ_g g ⊙ images[g] over `model_gains`."""
    out = fixed_image(terms, params, light)
    for n in model_gains:
        out = out + getattr(params, n)[None, :] * images[n]
    return out


def prepare_terms(
    gains: tuple[str, ...], scene, params, names, target, sqrt_weight, light: LightParams | None = None
) -> TargetTerms:
    """One target's terms: the geometry stage without the fragments hidden at
    FIT_TRANSMITTANCE_CUTOFF (`_geometry/_hidden`), and the images of the gains no fitted
    parameter reaches, at `params` — composited with every fragment the renderer draws, as
    the rest of the fixed image; `target` `[HW, 3]` and `sqrt_weight` `[HW, 1]` as
    `target_arrays` gives them. `light`: the light's start (or held) direction and colour;
    the lit images are then a white light's (the caller multiplies them by the colour)."""
    full, geom = geometry_stage(scene), geometry_stage(scene, cutoff=FIT_TRANSMITTANCE_CUTOFF)
    if light is not None and light.direction is not None:  # L of the light's direction
        to_light = lit_to_light(full, light)
        full, geom = (eqx.tree_at(lambda g: g.to_light, g, to_light) for g in (full, geom))
    direction = light is not None and "light_direction" in names
    model: AbstractShadingModel = geom.shading
    searched = tuple(n for n in model.searched if n in names)
    # §16: the streak factor scales a point's whole colour: it rides on both scales.
    streak = (
        jnp.ones((geom.tangent.shape[0], 1), geom.tangent.dtype)
        if geom.streak is None
        else geom.streak[:, None]
    )
    white = light is not None  # the colour multiplies the images instead
    light_scale = jnp.broadcast_to(streak, geom.tangent.shape) if white else geom.light_rgb[None, :] * streak
    points = shading_points(geom)
    reached, lit = _reaches(model, points, params, searched, direction)
    # Gains whose terms κ reaches inside the model (§19's scattered light), not through τ only.
    by_searched = {n: bool(p) for n, p in reached.items()}  # the light's direction too
    if "kappa" in searched and geom.omega is not None:  # τ moves every lit term
        reached = {n: p | ({"kappa"} if n in lit else set()) for n, p in reached.items()}
    varying = tuple(n for n in gains if reached[n])
    pairs = tuple((n, p) for n in varying for p in searched if p in reached[n])
    fixed_terms = TargetTerms(
        geometry=full,
        ambient_scale=streak,
        light=light_scale,
        fixed={},
        bases={},
        constant=jnp.zeros(()),
        target=jnp.asarray(target),
        sqrt_weight=jnp.asarray(sqrt_weight),
        varying=tuple(n for n in gains if n not in varying),
        searched=(),
        lit=lit,
    )
    reflectance = model.reflectance(points, params)  # at the start: the fixed terms' values
    fixed = gain_images_plain(fixed_terms, params, reflectance) if fixed_terms.varying else {}
    bases = {}
    # Bases hold the lit terms alone: a model with scattered terms recomputes them.
    if varying and not reflectance.scattered and not any(by_searched[n] for n in varying):
        bases = {n: {**reflectance.ambient, **reflectance.lit}[n] for n in varying}
    constant = full.transmittance[:, None] * full.backdrop
    return TargetTerms(
        geometry=geom,
        ambient_scale=streak,
        light=light_scale,
        fixed=fixed,
        bases=bases,
        constant=constant,
        target=jnp.asarray(target),
        sqrt_weight=jnp.asarray(sqrt_weight),
        varying=varying,
        searched=searched,
        lit=lit,
        pairs=pairs,
        direction=direction,
    )


def _reaches(model: AbstractShadingModel, points, params, searched, direction: bool = False):
    """({gain: the fitted searched parameters that reach its term inside the model}, the
    lit gains), by `dependence` on the model's `reflectance` (κ reaches a term there only
    through light scattered between fibres, §19; τ's κ the caller adds). With `direction`,
    "light_direction" reaches the terms that L reaches."""
    names = list(searched)

    def terms_of(*values):
        at = points if not direction else eqx.tree_at(lambda p: p.to_light, points, values[-1])
        r = model.reflectance(at, with_values(params, dict(zip(names, values)), ()))
        return r.ambient, r.lit, r.scattered

    values = [jnp.asarray(getattr(params, n)) for n in names]  # a scalar's or RGB's own shape
    inputs = [*names, "light_direction"] if direction else names
    ambient, lit, scattered = dependence(terms_of, *values, *([points.to_light] if direction else []))
    reached = {n: {inputs[i] for i in d} for n, d in {**ambient, **lit}.items()}
    for n, d in scattered.items():
        reached[n] = reached[n] | {inputs[i] for i in d}
    return reached, tuple(lit)


def rgb_searched(cls: type[AbstractShadingModel], params) -> tuple[str, ...]:
    """The searched parameters of `cls` that hold an RGB `[3]` value in `params` (each
    takes three solver coordinates, or one fitted as a grey value)."""
    # (An absent field, of a start of the wrong type that `fit` then refuses: not RGB.)
    return tuple(n for n in cls.searched if np.ndim(getattr(params, n, 0.0)) == 1)


@functools.cache
def fit_model(cls: type[AbstractShadingModel], rgb: tuple[str, ...] = ()) -> FitModel:
    """The fit of shading model class `cls` (one per class and `rgb`: a static part of the
    compiled steps). Its gains are solved for (`linear`), its `searched` parameters iterated
    on, those in `rgb` (`rgb_searched`) channel by channel. The model's `fittable` are fitted
    by default; the ambient gain, and a searched parameter not among them (an RGB absorption
    given besides melanin, say), only where named."""
    gains = tuple(n for n in cls.fittable if n not in cls.searched)
    all_gains = gains + (() if "ambient" in gains else ("ambient",))
    transforms = {**{n: SOFTPLUS for n in all_gains}, **dict(cls.searched)}

    def image(terms, params):
        return image_of(all_gains, terms, params, gain_images(terms, params))

    def images(terms, params):
        found = gain_images(terms, params)
        return fixed_image(terms, params), tuple((n, found[n]) for n in all_gains)

    return FitModel(
        label=cls.name,
        model_class=cls,
        params_type=cls.params_type,
        fittable=cls.fittable + tuple(n for n in (*all_gains, *cls.searched) if n not in cls.fittable),
        defaults=cls.fittable,
        colours=all_gains + tuple(rgb),
        transforms=transforms,
        prepare=functools.partial(prepare_terms, all_gains),
        image=image,
        linear=all_gains,
        gain_images=images,
        plateaus=tuple(cls.plateaus),
        grey=tuple(cls.grey),
    )


def target_image(terms: TargetTerms, params, plain: bool = False) -> jax.Array:
    """The target's RGB image `[HW, 3]` at `params` (with `plain`, through plain autodiff
    instead of the one-pass derivative rule; the tests compare the two)."""
    images = gain_images_plain(terms, params) if plain else gain_images(terms, params)
    names = tuple(images)
    return image_of(names, terms, params, images)
