"""A fit that fits the light, or holds it at a given value (docs/fitting.md, "Fitting the
light"): the `FitModel` of a shading model whose point is `LitParams`, the model's
parameters and the light's.

The image is the model's fit image (`_shading_fit.py`) with the light as an input of the
shading stage (docs/model.md §3): the lit gain images are those of a white light times the
light's colour c (the composite is linear in the point colours, and c is the same at every
point), so a fit of the colour alone keeps the one-pass derivative rule; where the light's
direction is fitted, the images it reaches are recomputed each step by plain autodiff. The
shadows Ω and V stay those of the scene's light, as the geometry stage computed them.
"""

from __future__ import annotations

import dataclasses
import functools

import jax.numpy as jnp

from .._shading import AbstractShadingModel
from .._shading._light import LightParams
from .._shading._transforms import LOG, Transform
from ._lit import LIGHT_NAMES, PLANE, LitParams, RelativeTransform
from ._model import FitModel
from ._result import FitError
from ._shading_fit import (
    TargetTerms,
    fit_model,
    fixed_image,
    gain_images,
    gain_images_plain,
    image_of,
    prepare_terms,
)

__all__ = ["LIGHT_TRANSFORMS", "lit_fit_model", "lit_images", "start_light"]

# light_direction: the tangent plane at the start (`_lit.PLANE`, a unit vector whatever
# the step); light_color: log space, as the exponents (c > 0; a step is a relative change).
LIGHT_TRANSFORMS: dict[str, Transform | RelativeTransform] = {"light_direction": PLANE, "light_color": LOG}


def start_light(scenes, names, light: LightParams | None) -> LightParams:
    """The light a fit starts from (and holds where not fitted): `light`'s fields where
    given, else the scenes' light (its colour; its direction only where fitted, so that
    an unfitted direction stays the geometry's). FitError where the scenes' lights differ,
    or for a direction (fitted or given) with a point light or an occluder."""
    if len({s.light for s in scenes}) > 1:
        raise FitError("a fit of the light needs scenes that share one light (their Ω is computed at it)")
    scene_light = scenes[0].light
    given = light is not None and light.direction is not None
    if given or "light_direction" in names:
        if scene_light.kind != "directional":
            raise FitError(
                "light_direction: the scene's light is a point light, whose geometry (position, "
                "L at every point) is kept; only a directional light's direction can be fitted"
            )
        if any(s.occluder is not None for s in scenes):
            raise FitError(
                "light_direction: not with an occluder (the geometry stage keeps the occluder's "
                "Lambert term, not its normals; docs/model.md §3)"
            )
    direction = light.direction if given and light is not None else None
    if direction is None and "light_direction" in names:
        direction = jnp.asarray(scene_light.direction, dtype=jnp.result_type(float))
    color = scene_light.color if light is None or light.color is None else light.color
    return LightParams(direction=direction, color=color)


def lit_images(terms: TargetTerms, lit: LitParams) -> dict:
    """{gain: its image K_g} at `lit`: the white light's lit images times the light's
    colour; through plain autodiff where the light's direction is fitted."""
    params, light = lit.shading, lit.light
    found = gain_images_plain(terms, params, light=light) if terms.direction else gain_images(terms, params)
    assert light.color is not None  # start_light always sets it
    return {n: image * light.color[None, :] if n in terms.lit else image for n, image in found.items()}


def _prepare(gains, scene, lit: LitParams, names, target, sqrt_weight) -> TargetTerms:
    terms = prepare_terms(gains, scene, lit.shading, names, target, sqrt_weight, light=lit.light)
    if "light_color" in names and terms.lit and set(terms.lit) <= set(names):
        # Every lit term is scaled by c and by its own gain: (s·c, g/s) is the same image
        # for every s > 0 and every fitted lit gain g (docs/fitting.md, "Fitting the light").
        raise FitError(
            f"light_color is degenerate with {', '.join(terms.lit)} fitted together (any s > 0 gives "
            "s·light_color and gains/s the same image): hold one of them (leave it out of fit)"
        )
    return terms


@functools.cache
def lit_fit_model(cls: type[AbstractShadingModel], rgb: tuple[str, ...] = ()) -> FitModel:
    """The fit of shading model class `cls` with the light: `fit_model(cls)`'s, whose
    point is `LitParams` and whose names include LIGHT_NAMES (one per class and `rgb`,
    as `fit_model`'s)."""
    base = fit_model(cls, rgb)
    gains = base.linear  # every gain, ambient included

    def image(terms, lit):
        return image_of(gains, terms, lit.shading, lit_images(terms, lit), lit.light)

    def images(terms, lit):
        found = lit_images(terms, lit)
        return fixed_image(terms, lit.shading, lit.light), tuple((n, found[n]) for n in gains)

    return dataclasses.replace(
        base,
        fittable=base.fittable + LIGHT_NAMES,
        colours=base.colours + ("light_color",),
        transforms={**base.transforms, **LIGHT_TRANSFORMS},
        prepare=functools.partial(_prepare, gains),
        image=image,
        gain_images=images,
    )
