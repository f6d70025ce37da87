"""The Kajiya-Kay fit's model-specific part (docs/model.md §6, §8; docs/fitting.md): the
per-target terms and the image as `FitModel` asks for them.

The image is linear in Kd, Ks and the ambient term:

    image = ambient⊙A + Kd⊙K_d(κ) + Ks⊙K_s(κ, p) + T·backdrop + T·O(κ),

A = composite(c), K_d = composite(τ·light·sin(T, L)·c), K_s = composite(τ·light·b^p)
(docs/model.md §6, §8); with an occluder, the backdrop is 0 at the pixels it covers and
O(κ) = k·ambient + exp(−κΩ)·V·k·light·max(N·L, 0) there (§13, `occluder_colors`). The geometry stage
runs once per target; Kajiya-Kay's geometric terms once per target; K_d is recomputed per
step only when κ is fitted, K_s only when κ or the shininess is, and otherwise a step is a
handful of per-pixel multiply-adds. Being
linear, the fitted gains are by default solved for (non-negative least squares) at every
step, and the solver iterates on the shininess and κ only (variable projection, `_varpro.py`).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._lookup import LOOKUP_MODELS, lookup_coordinates, lookup_terms
from .._render import composite, geometry_stage, occluder_colors
from .._scene import Scene
from .._shading import ShadingParams, kajiya_kay_terms, specular_power
from ._model import FitModel, Plateau
from ._problem import visible_fragments
from ._space import LOG, SOFTPLUS

__all__ = ["FITTABLE", "MODEL", "TargetTerms", "prepare_terms", "fixed_image", "point_terms",
           "kd_ks_images_plain", "kd_ks_images", "image", "gain_images", "target_image"]

FITTABLE = ("kd", "ks", "shininess", "kappa")
# The solver's space (docs/fitting.md): softplus for the colour gains, log for the
# scale-free exponent and extinction.
TRANSFORMS = {"kd": SOFTPLUS, "ks": SOFTPLUS, "shininess": LOG, "kappa": LOG}
# Where `fit` looks for a lower loss when it stops with every solved Ks at 0 (p then has no
# effect): the shininess on a log grid over the range we support, 1.5× apart.
SHININESS_SCAN = tuple(float(p) for p in np.geomspace(0.5, 1e4, 25))


class TargetTerms(eqx.Module):
    """Per target, everything a step needs that no fitted parameter reaches: the visible
    fragments, Kajiya-Kay's geometric terms per point, the fixed part of the image, and the
    target with its weights (`prepare_terms`)."""

    geometry: object
    sin_tl: jax.Array
    gap: jax.Array  # 1 − b per point (Kajiya-Kay, docs/model.md §8)
    lit_color: jax.Array  # light · c per point
    light: jax.Array
    omega: jax.Array | None
    constant: jax.Array  # ambient⊙A + T·backdrop, [HW, 3]
    ambient: jax.Array  # the held ambient, for the occluder's colour (§13)
    kd_image: jax.Array | None  # K_d when κ is fixed
    ks_image: jax.Array | None  # K_s when κ and p are fixed
    target: jax.Array
    sqrt_weight: jax.Array
    # Lookup models (§14): per point (u, v) and where the terms are lit; `gap` is then unused.
    lookup: tuple | None = None
    lookup_size: int = eqx.field(static=True, default=0)
    model: str = eqx.field(static=True, default="kajiya-kay")


def prepare_terms(scene: Scene, params: ShadingParams, names, target, sqrt_weight) -> TargetTerms:
    """One target's terms: the geometry stage, its visible fragments (`visible_fragments`),
    and what `names` leaves fixed precomputed at `params` (K_d without κ, K_s without κ
    and p); `target` `[HW, 3]` and `sqrt_weight` `[HW, 1]` as `target_arrays` gives them."""
    full = geometry_stage(scene)
    geom = visible_fragments(full)
    lookup = None
    if geom.model in LOOKUP_MODELS:  # §14: the same terms, read from the table
        lookup = lookup_coordinates(geom.tangent, geom.to_light, geom.to_eye)
        sin_tl, _ = lookup_terms(params.shininess, *lookup, geom.lookup_size, geom.model)
        gap = jnp.zeros_like(sin_tl)
    else:
        sin_tl, gap = jax.vmap(kajiya_kay_terms, in_axes=(0, 0, 0, None))(
            geom.tangent, geom.to_light, geom.to_eye, geom.model)
    # §16: the streak factor scales a point's whole colour, so it rides on the light (and
    # the ambient term): [P, 3] instead of [1, 3] with streaks.
    streak = 1.0 if geom.streak is None else geom.streak[:, None]
    light = geom.light_rgb[None, :] * streak
    lit_color = light * geom.base_color
    omega = geom.omega
    tau = None if omega is None else jnp.exp(-params.kappa * omega)
    # The fixed part of the image is computed once, with every fragment.
    # (The backdrop is 0 where the occluder covers the pixel: `fixed_image` adds its colour.)
    constant = (composite(full, params.ambient[None, :] * full.base_color * streak)
                + full.transmittance[:, None] * full.backdrop)
    kd_image = ks_image = None
    if "kappa" not in names or omega is None:
        scale = 1.0 if tau is None else tau[:, None]
        kd_image = composite(geom, scale * sin_tl[:, None] * lit_color)
        if "shininess" not in names:
            ks_image = composite(geom, scale * _specular_of(gap, lookup, geom, params.shininess)[:, None]
                                 * light)
    return TargetTerms(geom, sin_tl, gap, lit_color, light, omega, constant, params.ambient,
                       kd_image, ks_image, jnp.asarray(target), jnp.asarray(sqrt_weight), lookup,
                       geom.lookup_size, geom.model)


def _specular_of(gap, lookup, where, shininess):
    """max(b, 0)^p per point: the guarded power of the gap (§8), or the lookup table read
    at the points' (u, v) (§14); `where` carries the model and table size."""
    if lookup is None:
        return specular_power(gap, shininess)
    return lookup_terms(shininess, *lookup, where.lookup_size, where.model)[1]


def fixed_image(terms: TargetTerms, kappa):
    """ambient⊙A + T·backdrop + T·(the occluder's colour at κ, `occluder_colors`): the image
    without the fitted gains' terms Kd⊙K_d and Ks⊙K_s."""
    g = terms.geometry
    if g.occluder_pixel is None:
        return terms.constant
    occluder = occluder_colors(g, ShadingParams(ambient=terms.ambient, kappa=kappa))
    return terms.constant.at[g.occluder_pixel].add(g.transmittance[g.occluder_pixel][:, None] * occluder)


def point_terms(terms: TargetTerms, shininess, kappa):
    """Per point: the Kd and Ks colours before compositing, and their derivatives in κ and p:
    τ·sin·light·c, τ·b^p·light, ∂/∂κ of both (−Ω times them), ∂/∂p of the second."""
    tau = jnp.ones_like(terms.sin_tl) if terms.omega is None else jnp.exp(-kappa * terms.omega)
    omega = jnp.zeros_like(terms.sin_tl) if terms.omega is None else terms.omega
    if terms.lookup is None:
        spec = specular_power(terms.gap, shininess)
        # d(b^p)/dp through the same guarded power: 0 where b ≤ SPECULAR_BASE_EPS, never NaN.
        dspec = jax.vmap(jax.grad(specular_power, argnums=1), in_axes=(0, None))(terms.gap, shininess)
    else:  # §14: the table entries' derivative in p, interpolated like the entries
        spec, dspec = jax.jvp(lambda p: _specular_of(None, terms.lookup, terms, p), (shininess,),
                              (jnp.ones_like(shininess),))
    kd_col = (tau * terms.sin_tl)[:, None] * terms.lit_color
    ks_col = (tau * spec)[:, None] * terms.light
    dks_dp = (tau * dspec)[:, None] * terms.light
    return kd_col, ks_col, -omega[:, None] * kd_col, -omega[:, None] * ks_col, dks_dp


def kd_ks_images_plain(terms: TargetTerms, shininess, kappa):
    """(K_d, K_s) images `[HW, 3]` for this κ and shininess (precomputed ones pass through)."""
    kd_col, ks_col, *_ = point_terms(terms, shininess, kappa)
    kd_image = terms.kd_image if terms.kd_image is not None else composite(terms.geometry, kd_col)
    ks_image = terms.ks_image if terms.ks_image is not None else composite(terms.geometry, ks_col)
    return kd_image, ks_image


# The same function with the one-pass derivative rule below.
kd_ks_images = jax.custom_jvp(kd_ks_images_plain)


@kd_ks_images.defjvp
def _kd_ks_images_jvp(primals, tangents):
    """The images and their derivatives from one composite pass over all the channels.

    Everything here depends on the primal (κ, p) only; the tangent output is a per-pixel
    linear combination, so a Jacobian (vmap over tangent directions) batches only that,
    not the composites. `terms` is data: its tangent is ignored.
    """
    terms, shininess, kappa = primals
    _, d_shininess, d_kappa = tangents
    cols = point_terms(terms, shininess, kappa)
    images = composite(terms.geometry, jnp.concatenate(cols, axis=1))
    kd_image, ks_image, dkd_dk, dks_dk, dks_dp = jnp.split(images, 5, axis=1)
    if terms.kd_image is not None:  # κ is not fitted: K_d is fixed
        kd_image, dkd_dk = terms.kd_image, jnp.zeros_like(dkd_dk)
    if terms.ks_image is not None:
        ks_image, dks_dk, dks_dp = terms.ks_image, jnp.zeros_like(dks_dk), jnp.zeros_like(dks_dp)
    d_kd = dkd_dk * d_kappa
    d_ks = dks_dk * d_kappa + dks_dp * d_shininess
    return (kd_image, ks_image), (d_kd, d_ks)


def image(terms: TargetTerms, kd, ks, shininess, kappa, images=kd_ks_images):
    """The RGB image [HW, 3] of one target for the given parameter values.
    (`images=kd_ks_images_plain` gives plain autodiff, which the tests compare against.)"""
    kd_image, ks_image = images(terms, shininess, kappa)
    return fixed_image(terms, kappa) + kd[None, :] * kd_image + ks[None, :] * ks_image


def target_image(terms: TargetTerms, params: ShadingParams):
    """`image` at `params`: `FitModel.image`."""
    return image(terms, params.kd, params.ks, params.shininess, params.kappa)


def gain_images(terms: TargetTerms, params: ShadingParams):
    """(the fixed image, ((gain, its image), ...)): `FitModel.gain_images`, image =
    fixed + Σ gain⊙(its image)."""
    kd_image, ks_image = kd_ks_images(terms, params.shininess, params.kappa)
    return fixed_image(terms, params.kappa), (("kd", kd_image), ("ks", ks_image))


MODEL = FitModel(
    label="Kajiya-Kay", shading_models=("kajiya-kay", "kajiya-kay-mirror", *LOOKUP_MODELS),
    params_type=ShadingParams, fittable=FITTABLE, colours=("kd", "ks"), transforms=TRANSFORMS,
    prepare=prepare_terms, image=target_image,
    # Kd and Ks enter the image linearly (module docstring): with `separable`, `fit` solves
    # whichever of them are fitted and the solver iterates on p and κ only.
    linear=("kd", "ks"), gain_images=gain_images,
    plateau=Plateau(gain="ks", exponent="shininess", scan=tuple(np.log(p) for p in SHININESS_SCAN)),
)
