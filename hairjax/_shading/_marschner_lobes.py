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
    "logistic_scale",
    "azimuthal_quadrature",
    "Azimuthal",
]

Lobes = tuple[Float[Array, ""], Float[Array, " 3"], Float[Array, " 3"]]


def lobe_widths(beta_m: Float[Array, ""]) -> Float[Array, " 3"]:
    """The Gaussians' standard deviations (R, TT, TRT) from the longitudinal roughness β_m
    (Chiang et al. 2016's fit of d'Eon's variance: √v = 0.726 β + 0.812 β² + 3.7 β²⁰;
    √(v/4) and √(4v) for TT and TRT)."""
    std = 0.726 * beta_m + 0.812 * beta_m**2 + 3.7 * beta_m**20
    return jnp.stack([std, 0.5 * std, 2.0 * std])


def logistic_scale(beta_n: Float[Array, ""]) -> Float[Array, ""]:
    """The azimuthal logistic's scale s from the azimuthal roughness β_n (Chiang et al.
    2016, Mitsuba's `update`: s = √(π/8)(0.265 β + 1.194 β² + 5.372 β²²))."""
    return jnp.sqrt(jnp.pi / 8.0) * (0.265 * beta_n + 1.194 * beta_n**2 + 5.372 * beta_n**22)


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


class Azimuthal(NamedTuple):
    """The azimuthal scattering N_p as Chiang et al. 2016's far field: `roughness` β_n and
    the quadrature's `samples` over the fibre's width (`azimuthal_quadrature`)."""

    roughness: Float[Array, ""]
    samples: int


def _wrap(x: Float[Array, "*s"]) -> Float[Array, "*s"]:
    """x moved into [−π, π] by whole turns (Mitsuba's fmod in `azimuthal_scattering`)."""
    return x - 2.0 * jnp.pi * jnp.round(x / (2.0 * jnp.pi))


def _trimmed_logistic(x: Float[Array, "*s"], s: Float[Array, ""]) -> Float[Array, "*s"]:
    """Chiang's trimmed logistic on [−π, π]: e^{−|x|/s} / (s(1 + e^{−|x|/s})²) over its mass
    there, 1 − 2/(1 + e^{π/s}). Symmetric, so |x|'s kink at 0 has no effect on the value."""
    e = jnp.exp(-jnp.abs(x) / s)
    mass = 1.0 - 2.0 / (1.0 + jnp.exp(jnp.pi / s))
    return e / (s * (1.0 + e) ** 2) / mass


def azimuthal_quadrature(
    phi: Float[Array, ""],
    cos_d: Float[Array, ""],
    a: Float[Array, ""],
    cos_t: Float[Array, ""],
    sigma_a: Float[Array, " 3"],
    azimuthal: Azimuthal,
) -> tuple[Float[Array, ""], Float[Array, " 3"], Float[Array, " 3"], Float[Array, " 3"]]:
    """(N_R, N_TT, N_TRT, A_3+) of the far field (d'Eon et al. 2011; Chiang et al. 2016's
    attenuations and logistic): N_p(φ) = ½ ∫ A_p(h) D_s(φ − Φ_p(h)) dh over the offset
    h ∈ [−1, 1], Φ_p = 2pγ_t − 2γ_i + pπ, h = sin γ_i, sin γ_t = h/η'; and the remainder's
    attenuation ½ ∫ A_3+(h) dh. The midpoint rule in γ_i (dh = cos γ_i dγ_i, where Φ_p moves
    at most 2 per unit of γ_i, unlike in h, where it is infinite at ±1), `samples` nodes."""
    n = azimuthal.samples
    gamma_i = (jnp.arange(n, dtype=cos_d.dtype) + 0.5) * (jnp.pi / n) - 0.5 * jnp.pi
    h = jnp.sin(gamma_i)
    weight = jnp.cos(gamma_i) * (0.5 * jnp.pi / n)
    gamma_t = jnp.arcsin(h * a)  # |h·a| ≤ 1/η < 1: arcsin's derivative stays finite
    t = jnp.exp(-sigma_a[None, :] * (2.0 * jnp.cos(gamma_t) / cos_t)[:, None])
    f = fresnel_dielectric(cos_d * jnp.cos(gamma_i))[:, None]
    attenuation = (f[:, 0], (1.0 - f) ** 2 * t, (1.0 - f) ** 2 * f * t * t)
    s = logistic_scale(azimuthal.roughness)
    out = []
    for p, a_p in enumerate(attenuation):
        d = _trimmed_logistic(_wrap(phi - (2.0 * p * gamma_t - 2.0 * gamma_i + p * jnp.pi)), s)
        out.append(jnp.tensordot(weight * d, a_p, axes=(0, 0)))
    series = 1.0 - f * t
    # Double-where: fires only where f·T → 1 (grazing and no absorption); the remainder is 0 there.
    ok = series > HAIR_SERIES_EPS
    rest = jnp.where(ok, attenuation[2] * f * t / jnp.where(ok, series, 1.0), 0.0)
    return out[0], out[1], out[2], jnp.tensordot(weight, rest, axes=(0, 0))


def marschner_lobes(
    tangent: Float[Array, " 3"],
    to_light: Float[Array, " 3"],
    to_eye: Float[Array, " 3"],
    sigma_a: Float[Array, " 3"],
    beta_m: Float[Array, ""],
    tilt: Float[Array, ""],
    azimuthal: Azimuthal | None = None,
) -> Lobes:
    """(R, TT, TRT): π·M_p·N_p of each lobe at one point, R a scalar (the surface
    reflection has no colour), TT and TRT RGB (absorbed by σ_a per unit fibre radius).
    `tilt` is the scales' angle α in degrees. `azimuthal`: None for Karis's azimuthal
    approximations, else Chiang's far field by quadrature (`azimuthal_quadrature`). Zero
    vectors (§1: no tangent, a point light at the point) give finite values; the shading
    stage's terms are 0 there through L."""
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
    cos_phi = jnp.dot(lp, vp)
    cos_half = 0.5 * safe_norm(lp + vp)

    widths = lobe_widths(beta_m)
    alpha = jnp.deg2rad(tilt)
    m_r = gaussian(widths[0], sin_l + _tilted(sin_v, cos_v, -2.0 * alpha))
    m_tt = gaussian(widths[1], sin_l + _tilted(sin_v, cos_v, alpha))
    m_trt = gaussian(widths[2], sin_l + _tilted(sin_v, cos_v, 4.0 * alpha))
    m_rest = gaussian(widths[2], sin_l + sin_v)

    # a = 1/η' = cos θ_d / √(η² − sin²θ_d): no division by cos θ_d, which is 0 at grazing
    # incidence; η² − sin²θ_d ≥ η² − 1 > 0.
    a = cos_d / jnp.sqrt(HAIR_ETA**2 - 1.0 + cos_d * cos_d)
    # cos θ_t = √(1 − sin²θ_d/η²) ≥ √(1 − 1/η²) > 0.
    cos_t = jnp.sqrt(1.0 - (1.0 - cos_d * cos_d) / HAIR_ETA**2)

    if azimuthal is not None:
        # φ ∈ [0, π] by atan2 of (‖L̂p × V̂p‖, L̂p·V̂p): no acos, whose derivative is infinite
        # at φ = 0 and π; N_p is even in φ (Φ_p is odd in h), so the sign is not needed.
        phi = jnp.arctan2(safe_norm(jnp.cross(lp, vp)), cos_phi)
        n_r, n_tt, n_trt, a_rest = azimuthal_quadrature(phi, cos_d, a, cos_t, sigma_a, azimuthal)
        trt = jnp.pi * (m_trt * n_trt + m_rest * a_rest / (2.0 * jnp.pi))
        return jnp.pi * m_r * n_r, jnp.pi * m_tt * n_tt, trt

    def transmittance(h):
        cos_gamma_t = jnp.sqrt(1.0 - (h * a) ** 2)  # h·a ≤ 1/η < 1
        return jnp.exp(-sigma_a * (2.0 * cos_gamma_t / cos_t))

    r = jnp.pi * m_r * 0.25 * cos_half * fresnel_dielectric(cos_d * cos_half)

    h_tt = cos_half * (1.0 + a * (KARIS_TT[0] - KARIS_TT[1] * cos_phi))
    f_tt = fresnel_dielectric(cos_d * _safe_sqrt(1.0 - h_tt * h_tt))
    d_tt = jnp.exp(-KARIS_TT[2] * cos_phi - KARIS_TT[3])
    tt = jnp.pi * m_tt * (1.0 - f_tt) ** 2 * transmittance(h_tt) * d_tt

    f_trt = fresnel_dielectric(cos_d * jnp.sqrt(1.0 - HAIR_TRT_OFFSET**2))
    t_trt = transmittance(jnp.asarray(HAIR_TRT_OFFSET))
    a_trt = (1.0 - f_trt) ** 2 * f_trt * t_trt * t_trt
    d_trt = jnp.exp(KARIS_TRT[0] * cos_phi - KARIS_TRT[1])
    series = 1.0 - f_trt * t_trt
    # Double-where: fires only where f·T → 1 (grazing and no absorption); the remainder is 0 there.
    ok = series > HAIR_SERIES_EPS
    a_rest = jnp.where(ok, a_trt * f_trt * t_trt / jnp.where(ok, series, 1.0), 0.0)
    trt = jnp.pi * (m_trt * a_trt * d_trt + m_rest * a_rest / (2.0 * jnp.pi))
    return r, tt, trt
