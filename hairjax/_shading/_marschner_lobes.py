"""The Marschner-family fibre lobes R, TT and TRT at one point, in Karis's real-time
factorisation (docs/model.md §19): pure JAX functions written for one point (the model
vmaps them), differentiable in the absorption σ_a, the longitudinal roughness β_m and the
cuticle tilt α.

Sources, each formula where it is used:

- Karis 2016, "Physically Based Hair Shading in Unreal" (SIGGRAPH course): the
  factorisation S = Σ_p M_p(θ_i, θ_o) N_p(φ), M_p a Gaussian in sin θ_i + sin θ_o, the
  azimuthal approximations N_R = ¼ cos(φ/2) A_R, N_TT = A_TT(h_TT) e^{−3.65 cos φ − 3.98}
  with h_TT = cos(φ/2)(1 + a(0.6 − 0.8 cos φ)), N_TRT = A_TRT(√3/2) e^{17 cos φ − 16.78};
- Chiang et al. 2016 (as Mitsuba 3's `hair` BSDF, `src/bsdfs/hair.cpp`, implements it):
  the lobe variances from β_m, v = (0.726 β + 0.812 β² + 3.7 β²⁰)², v_R = v, v_TT = v/4,
  v_TRT = 4v; the tilt of the scales, θ → θ − 2α (R), θ + α (TT), θ + 4α (TRT), applied to
  the direction toward the eye; the attenuations A_0 = f, A_1 = (1 − f)²T,
  A_2 = A_1 f T, the remainder A_3+ = A_2 f T/(1 − f T) with the TRT variance, no tilt
  and a uniform azimuth 1/(2π); the path length 2 cos γ_t / cos θ_t (radius 1) and
  sin θ_t = sin θ / η;
- d'Eon et al. 2011 and Marschner et al. 2003: the Bravais index η' =
  √(η² − sin²θ_d)/cos θ_d that a = 1/η' comes from, and the unpolarised dielectric
  Fresnel reflectance.

Conventions: T the unit tangent (root to tip), L toward the light, V toward the eye;
sin θ = T·X and cos θ = ‖T × X‖ for X = L, V; φ the angle between L and V projected on
the normal plane; θ_d = (θ_V − θ_L)/2. The returned lobes are π·M_p·N_p: a light of
hairjax colour c is an irradiance π·c (docs/reference.md, "The mapping"), and a fibre
lit by irradiance E has radiance E·Σ M_p N_p (Chiang et al. 2016: the BSDF's 1/|cos|
cancels the rendering equation's cosine).
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp
from jaxtyping import Array, Float

from .._constants import HAIR_ETA, HAIR_SERIES_EPS, HAIR_TRT_OFFSET, KARIS_TRT, KARIS_TT
from .._vectors import safe_norm, safe_normalize

__all__ = [
    "lobe_widths",
    "fresnel_dielectric",
    "marschner_lobes",
    "Lobes",
    "FibreAngles",
    "fibre_angles",
    "longitudinal_arguments",
    "azimuthal_lobes",
    "gaussian",
    "TILT_MULTIPLES",
]

Lobes = tuple[Float[Array, ""], Float[Array, " 3"], Float[Array, " 3"]]


def lobe_widths(beta_m: Float[Array, ""]) -> Float[Array, " 3"]:
    """The Gaussians' standard deviations (R, TT, TRT) from the longitudinal roughness β_m
    (Chiang et al. 2016's fit of d'Eon's variance: √v = 0.726 β + 0.812 β² + 3.7 β²⁰;
    √(v/4) and √(4v) for TT and TRT)."""
    std = 0.726 * beta_m + 0.812 * beta_m**2 + 3.7 * beta_m**20
    return jnp.stack([std, 0.5 * std, 2.0 * std])


def fresnel_dielectric(cos_i: Float[Array, "*s"], eta: float = HAIR_ETA) -> Float[Array, "*s"]:
    """Unpolarised Fresnel reflectance of light arriving from air at cosine `cos_i` ∈ [0, 1]
    onto a dielectric of index η > 1 (no total internal reflection from outside):
    ½(r_s² + r_p²), r_s = (c − ηc_t)/(c + ηc_t), r_p = (ηc − c_t)/(ηc + c_t)."""
    # Fires where cos_i rounds above 1 (unit vectors off by an ulp); 1 − cos² ≥ 0 then.
    cos_i = jnp.clip(cos_i, 0.0, 1.0)
    # cos_t ≥ √(1 − 1/η²) > 0: no guard needed, and the denominators are ≥ η·cos_t > 0.
    cos_t = jnp.sqrt(1.0 - (1.0 - cos_i * cos_i) / (eta * eta))
    r_s = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    r_p = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return 0.5 * (r_s * r_s + r_p * r_p)


def _safe_sqrt(x: Float[Array, "*s"]) -> Float[Array, "*s"]:
    """√max(x, 0) with a zero gradient at x ≤ 0 (double-where: fires at the end of a
    range, cos θ_d = 0 or h = 1, where d√x/dx = ∞ would give NaN in the backward pass)."""
    positive = x > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, x, 1.0)), 0.0)


def gaussian(std: Array, x: Array) -> Array:
    """Karis's M_p: the normal density g(std; x), elementwise with broadcasting (std > 0:
    β_m > 0 is checked on input)."""
    return jnp.exp(-0.5 * (x / std) ** 2) / (jnp.sqrt(2.0 * jnp.pi) * std)


def _tilted(sin_t: Float[Array, ""], cos_t: Float[Array, ""], angle: Float[Array, ""]) -> Float[Array, ""]:
    """sin(θ + angle) from sin θ and cos θ (Mitsuba's reframe of the scales' tilt)."""
    return sin_t * jnp.cos(angle) + cos_t * jnp.sin(angle)


class FibreAngles(NamedTuple):
    """The angles every lobe reads at one point (module docstring's conventions)."""

    sin_l: Float[Array, ""]
    sin_v: Float[Array, ""]
    cos_l: Float[Array, ""]
    cos_v: Float[Array, ""]
    cos_d: Float[Array, ""]
    cos_phi: Float[Array, ""]
    cos_half: Float[Array, ""]


def fibre_angles(
    tangent: Float[Array, " 3"], to_light: Float[Array, " 3"], to_eye: Float[Array, " 3"]
) -> FibreAngles:
    """sin θ and cos θ of L and V, cos θ_d, cos φ and cos(φ/2) at one point, every one
    finite for zero vectors (§1) and for L or V along the fibre."""
    sin_l, sin_v = jnp.dot(tangent, to_light), jnp.dot(tangent, to_eye)
    cos_l, cos_v = safe_norm(jnp.cross(tangent, to_light)), safe_norm(jnp.cross(tangent, to_eye))
    # cos θ_d = cos((θ_V − θ_L)/2) = √((1 + cos(θ_V − θ_L))/2), without asin at ±1; the
    # argument is 0 only for L and V along the fibre, opposite (θ_V − θ_L = ±π).
    cos_d = _safe_sqrt(0.5 * (1.0 + cos_l * cos_v + sin_l * sin_v))
    # φ from the directions projected on the normal plane; cos(φ/2) = ‖L̂p + V̂p‖/2 needs no
    # √(½ + ½cos φ), whose derivative is infinite at φ = π (back-lit). A projection is 0 for
    # L or V along the fibre (θ = ±90°): then cos φ = 0 and cos(φ/2) = ½, finite.
    lp = safe_normalize(to_light - sin_l * tangent)
    vp = safe_normalize(to_eye - sin_v * tangent)
    return FibreAngles(sin_l, sin_v, cos_l, cos_v, cos_d, jnp.dot(lp, vp), 0.5 * safe_norm(lp + vp))


# The scales' tilt of each longitudinal lobe, as a multiple of α added to θ_V (R, TT, TRT;
# the TRT remainder has none): Mitsuba's reframe.
TILT_MULTIPLES = (-2.0, 1.0, 4.0, 0.0)


def longitudinal_arguments(angles: FibreAngles, tilt: Float[Array, ""]) -> Float[Array, " 4"]:
    """The arguments of M_R, M_TT, M_TRT and the remainder's M: sin θ_L + sin(θ_V + kα),
    k from TILT_MULTIPLES, `tilt` α in degrees."""
    alpha = jnp.deg2rad(tilt)
    return jnp.stack([angles.sin_l + _tilted(angles.sin_v, angles.cos_v, k * alpha) for k in TILT_MULTIPLES])


def azimuthal_lobes(
    cos_d: Float[Array, ""],
    cos_phi: Float[Array, ""],
    cos_half: Float[Array, ""],
    sigma_a: Float[Array, " 3"],
) -> tuple[Float[Array, ""], Float[Array, " 3"], Float[Array, " 3"], Float[Array, " 3"]]:
    """A_p·N_p of R, TT, TRT and of the TRT remainder (uniform, A_3+/(2π)) at θ_d and φ:
    the azimuthal factors of Karis's approximations (module docstring), the lobes being
    π·M_p·(A_p N_p). Their integral over φ ∈ (−π, π] is the lobe's share of the light the
    fibre scatters (dual scattering's tables integrate them, `_dual_scattering.py`)."""
    # a = 1/η' = cos θ_d / √(η² − sin²θ_d): no division by cos θ_d, which is 0 at grazing
    # incidence; η² − sin²θ_d ≥ η² − 1 > 0.
    a = cos_d / jnp.sqrt(HAIR_ETA**2 - 1.0 + cos_d * cos_d)
    # cos θ_t = √(1 − sin²θ_d/η²) ≥ √(1 − 1/η²) > 0.
    cos_t = jnp.sqrt(1.0 - (1.0 - cos_d * cos_d) / HAIR_ETA**2)

    def transmittance(h):
        cos_gamma_t = jnp.sqrt(1.0 - (h * a) ** 2)  # h·a ≤ 1/η < 1
        return jnp.exp(-sigma_a * (2.0 * cos_gamma_t / cos_t))

    n_r = 0.25 * cos_half * fresnel_dielectric(cos_d * cos_half)

    h_tt = cos_half * (1.0 + a * (KARIS_TT[0] - KARIS_TT[1] * cos_phi))
    f_tt = fresnel_dielectric(cos_d * _safe_sqrt(1.0 - h_tt * h_tt))
    d_tt = jnp.exp(-KARIS_TT[2] * cos_phi - KARIS_TT[3])
    n_tt = (1.0 - f_tt) ** 2 * transmittance(h_tt) * d_tt

    f_trt = fresnel_dielectric(cos_d * jnp.sqrt(1.0 - HAIR_TRT_OFFSET**2))
    t_trt = transmittance(jnp.asarray(HAIR_TRT_OFFSET))
    a_trt = (1.0 - f_trt) ** 2 * f_trt * t_trt * t_trt
    d_trt = jnp.exp(KARIS_TRT[0] * cos_phi - KARIS_TRT[1])
    series = 1.0 - f_trt * t_trt
    # Double-where: fires only where f·T → 1 (grazing and no absorption); the remainder is 0 there.
    ok = series > HAIR_SERIES_EPS
    a_rest = jnp.where(ok, a_trt * f_trt * t_trt / jnp.where(ok, series, 1.0), 0.0)
    return n_r, n_tt, a_trt * d_trt, a_rest / (2.0 * jnp.pi)


def marschner_lobes(
    tangent: Float[Array, " 3"],
    to_light: Float[Array, " 3"],
    to_eye: Float[Array, " 3"],
    sigma_a: Float[Array, " 3"],
    beta_m: Float[Array, ""],
    tilt: Float[Array, ""],
) -> Lobes:
    """(R, TT, TRT): π·M_p·N_p of each lobe at one point, R a scalar (the surface
    reflection has no colour), TT and TRT RGB (absorbed by σ_a per unit fibre radius).
    `tilt` is the scales' angle α in degrees. Zero vectors (§1: no tangent, a point light
    at the point) give finite values; the shading stage's terms are 0 there through L."""
    angles = fibre_angles(tangent, to_light, to_eye)
    widths = lobe_widths(beta_m)
    args = longitudinal_arguments(angles, tilt)
    m_r, m_tt, m_trt = (gaussian(widths[i], args[i]) for i in range(3))
    m_rest = gaussian(widths[2], args[3])
    n_r, n_tt, n_trt, n_rest = azimuthal_lobes(angles.cos_d, angles.cos_phi, angles.cos_half, sigma_a)
    return jnp.pi * m_r * n_r, jnp.pi * m_tt * n_tt, jnp.pi * (m_trt * n_trt + m_rest * n_rest)
