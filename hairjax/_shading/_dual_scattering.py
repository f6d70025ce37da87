"""Dual scattering (Zinke, Yuksel, Weber & Keyser 2008, "Dual Scattering Approximation for
Fast Multiple Scattering in Hair"): light scattered between fibres, for the `marschner`
model's `multiple_scattering = "dual"` (docs/model.md §19, "Dual scattering").

Light reaching a point through n fibres is split into the direct part (the shadow's τ)
and a forward-scattered part, spread longitudinally and attenuated by the fibres' average
forward attenuation ā_f (global multiple scattering); the neighbourhood of the point adds
light scattered back to it (local multiple scattering, f_back). The per-θ quantities
(ā_f, ā_b, the lobes' average shifts and widths, A_b, Δ_b, σ_b, and the forward-scattered
azimuthal functions N^G_p) are computed here, in JAX, by quadrature of the model's own
azimuthal lobes (`azimuthal_lobes`) on a small grid of the light's inclination, so they
are differentiable in σ_a, β_m and the tilt; each point interpolates them.

Units: the model's longitudinal Gaussians are in x = sin θ_L + sin θ_V (Karis), so every
shift and width here is in x, where the paper's are in θ_h = (θ_L + θ_V)/2 ≈ x/2; only
σ_b's formula (not homogeneous in the widths) is evaluated in the paper's unit.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax.scipy.special import ndtr
from jaxtyping import Array, Float

from ._marschner_lobes import (
    TILT_MULTIPLES,
    azimuthal_lobes,
    fibre_angles,
    gaussian,
    lobe_widths,
    longitudinal_arguments,
)

__all__ = [
    "DualTables",
    "dual_tables",
    "dual_terms",
    "dual_terms_batched",
    "DENSITY_FORWARD",
    "DENSITY_BACK",
]

# Zinke et al. 2008's density factors d_f, d_b of the forward and backward scattering
# through a hair volume: 0.7, the value the paper gives (Unity HDRP uses the same).
DENSITY_FORWARD = 0.7
DENSITY_BACK = 0.7

# The grids: the light's sin θ and cos φ on [−1, 1] (uniform, so a point's cell is found by
# arithmetic), and Gauss-Legendre nodes on each half of the azimuth.
_N_THETA = 33
_N_PHI = 17
_N_QUAD = 32
# Below this 1 − ā_f² the back-scatter's geometric series would diverge: ā_f → 1 only if
# the fibre sent all light forward, which its R lobe (Fresnel ≥ 4.6 %, half of it
# backward) rules out; the clamp keeps the tables finite for any σ_a ≥ 0.
_MAX_FORWARD = 1.0 - 1e-4


class DualTables(NamedTuple):
    """Dual scattering's quantities on the grid of the light's sin θ (`[J, …]`), RGB last:
    `a_f`, `a_b` the average forward and backward attenuations ā_f, ā_b; `var_f` the
    forward lobes' average variance β̄_f² (x units); `a_back` A_b, `shift_back` Δ_b,
    `std_back` σ_b; `share_back` `[J, 3, 3]` each lobe's share a_b^p/ā_b of the backward
    attenuation (R, TT, TRT); `n_g` `[J, K, 3, 3]` the forward-scattered azimuthal
    functions N^G_p on the (sin θ, cos φ) grid."""

    a_f: Float[Array, "J 3"]
    a_b: Float[Array, "J 3"]
    var_f: Float[Array, "J 3"]
    a_back: Float[Array, "J 3"]
    shift_back: Float[Array, "J 3"]
    std_back: Float[Array, "J 3"]
    share_back: Float[Array, "J 3 3"]
    n_g: Float[Array, "J K 3 3"]


def _lobe_rows(cos_d, cos_phi, cos_half, sigma_a) -> Float[Array, "... 4 3"]:
    """A_p N_p of R, TT, TRT and the remainder as `[..., 4, 3]` (R broadcast to RGB)."""
    fn = jnp.vectorize(
        lambda d, c, h: jnp.stack([jnp.broadcast_to(x, (3,)) for x in azimuthal_lobes(d, c, h, sigma_a)]),
        signature="(),(),()->(4,3)",
    )
    shape = jnp.broadcast_shapes(jnp.shape(cos_d), jnp.shape(cos_phi), jnp.shape(cos_half))
    return fn(*(jnp.broadcast_to(x, shape) for x in (cos_d, cos_phi, cos_half)))


def _half_integrals(
    cos_d: Float[Array, " J"], sigma_a
) -> tuple[Float[Array, "J 4 3"], Float[Array, "J 4 3"]]:
    """Per lobe, ∫ A_p N_p dφ over the forward half (π/2 < |φ| ≤ π) and the backward half
    (|φ| < π/2), each by Gauss-Legendre on φ ∈ [0, π/2] or [π/2, π] doubled (N_p is even in
    φ). Zinke et al.'s ā_f, ā_b (their eqs. 6 and 11) are the sums over the lobes; the
    longitudinal Gaussians integrate to 1 over the sphere's θ_V and are left out."""
    nodes, weights = np.polynomial.legendre.leggauss(_N_QUAD)

    def half(lo):
        phi = lo + (nodes + 1.0) * (np.pi / 4.0)  # [lo, lo + π/2]
        w = jnp.asarray(weights * (np.pi / 4.0) * 2.0, dtype=sigma_a.dtype)
        rows = _lobe_rows(cos_d[:, None], jnp.asarray(np.cos(phi)), jnp.asarray(np.cos(phi / 2.0)), sigma_a)
        return jnp.einsum("q,jqpc->jpc", w, rows)

    return half(np.pi / 2.0), half(0.0)


def _forward_azimuth(cos_d: Float[Array, " J"], sigma_a) -> Float[Array, "J K 4 3"]:
    """N^G_p(θ, φ) = (1/π) ∫_{−π/2}^{π/2} N_p(θ, φ − φ') dφ' (Zinke et al. 2008, eq. 25):
    light forward-scattered toward the point arrives with its azimuth spread over the
    forward half, on the grid of cos φ."""
    nodes, weights = np.polynomial.legendre.leggauss(_N_QUAD)
    phi = np.arccos(np.linspace(-1.0, 1.0, _N_PHI))  # φ at the grid's cos φ = −1 … 1
    psi = phi[:, None] - nodes[None, :] * (np.pi / 2.0)  # φ − φ', φ' on (−π/2, π/2)
    psi = np.abs(np.where(psi > np.pi, 2.0 * np.pi - psi, psi))  # folded into [0, π]
    w = jnp.asarray(weights * 0.5, dtype=sigma_a.dtype)  # (1/π)·(π/2)·w_q
    rows = _lobe_rows(cos_d[:, None, None], jnp.asarray(np.cos(psi)), jnp.asarray(np.cos(psi / 2.0)), sigma_a)
    return jnp.einsum("q,jkqpc->jkpc", w, rows)


def _back_scatter(a_f, a_b, shift_f, shift_b, var_f, var_b):
    """A_b, Δ_b and σ_b from the averages (Zinke et al. 2008, eqs. 14, 16, 17: one and three
    backward scattering events between any number of forward ones). Widths in x units in
    and out; eq. 17 in θ_h units (x/2), where the paper writes it."""
    af2, ab2 = a_f * a_f, a_b * a_b
    rest = 1.0 - af2
    a_back = a_b * af2 / rest + a_b * ab2 * af2 / rest**3
    shift = shift_b * (1.0 - 2.0 * ab2 / rest**2) + shift_f * (2.0 * rest**2 + 4.0 * af2 * ab2) / rest**3
    beta_f2, beta_b2 = var_f / 4.0, var_b / 4.0  # θ_h units
    beta_f, beta_b = jnp.sqrt(beta_f2), jnp.sqrt(beta_b2)  # > 0: every lobe width is (β_m > 0)
    std = (
        (1.0 + DENSITY_BACK * af2)
        * (a_b * jnp.sqrt(2.0 * beta_f2 + beta_b2) + a_b * ab2 * jnp.sqrt(2.0 * beta_f2 + 3.0 * beta_b2))
        / (a_b + a_b * ab2 * (2.0 * beta_f + 3.0 * beta_b))
    )
    return a_back, shift, 2.0 * std


def _longitudinal_mass(sin_t: np.ndarray, widths, alpha) -> Float[Array, "J 4"]:
    """Per lobe, the share of M_p's Gaussian inside the sphere: its argument
    sin θ_L + sin(θ_V + kα) ≈ sin θ_L + sin θ_V + kα·cos θ_L near the specular cone spans
    [sin θ_L − 1, sin θ_L + 1] + kα·cos θ_L as sin θ_V spans [−1, 1] (Karis's Gaussian is in
    sin θ: at grazing light part of it falls outside, and the lobe loses that light)."""
    cos_t = np.sqrt(1.0 - sin_t * sin_t)
    k = np.asarray(TILT_MULTIPLES)
    centre = jnp.asarray(sin_t[:, None]) + jnp.asarray(k[None, :] * cos_t[:, None]) * alpha  # [J, 4]
    w = jnp.stack([widths[0], widths[1], widths[2], widths[2]])[None, :]
    return ndtr((centre + 1.0) / w) - ndtr((centre - 1.0) / w)


@jax.jit  # one compiled program where it is called outside a jit (its many small ops)
def dual_tables(sigma_a: Float[Array, " 3"], beta_m: Float[Array, ""], tilt: Float[Array, ""]) -> DualTables:
    """The tables from the model's lobes at σ_a, β_m and tilt α (degrees), on the grid of
    the light's sin θ: per lobe p the attenuations a_f^p, a_b^p (the half-azimuth integrals
    at θ_d = θ, the specular cone, times the share of M_p inside the sphere), its shift
    α_p = −k_p·α·cos θ (x units: the peak of M_p, `TILT_MULTIPLES`) and width β_p
    (`lobe_widths`); ā = Σ_p a^p, and ᾱ, β̄² the lobes' shifts and variances weighted
    by a^p (Zinke et al. 2008's average shifts and widths), then A_b, Δ_b, σ_b
    (`_back_scatter`)."""
    sin_t = np.linspace(-1.0, 1.0, _N_THETA)
    cos_t = jnp.asarray(np.sqrt(1.0 - sin_t * sin_t), dtype=sigma_a.dtype)
    widths = lobe_widths(beta_m)
    alpha = jnp.deg2rad(tilt)
    mass = _longitudinal_mass(sin_t, widths, alpha)[:, :, None]
    forward, backward = (mass * h for h in _half_integrals(cos_t, sigma_a))  # [J, 4, 3]
    var = jnp.stack([widths[0], widths[1], widths[2], widths[2]]) ** 2  # [4]
    shift = -jnp.asarray(TILT_MULTIPLES, sigma_a.dtype)[None, :] * alpha * cos_t[:, None]  # [J, 4]
    # ā > 0: the R lobe's attenuation alone is (Fresnel ≥ 4.6 %, at least half of M_R inside).
    a_f, a_b = forward.sum(axis=1), backward.sum(axis=1)
    shift_f = jnp.einsum("jpc,jp->jc", forward, shift) / a_f
    shift_b = jnp.einsum("jpc,jp->jc", backward, shift) / a_b
    var_f = jnp.einsum("jpc,p->jc", forward, var) / a_f
    var_b = jnp.einsum("jpc,p->jc", backward, var) / a_b
    a_back, shift_back, std_back = _back_scatter(
        jnp.minimum(a_f, _MAX_FORWARD), a_b, shift_f, shift_b, var_f, var_b
    )
    lobes3 = backward.at[:, 2].add(backward[:, 3])[:, :3]  # the remainder belongs to TRT
    n_g = _forward_azimuth(cos_t, sigma_a)
    n_g = n_g.at[:, :, 2].add(n_g[:, :, 3])[:, :, :3]
    return DualTables(a_f, a_b, var_f, a_back, shift_back, std_back, lobes3 / a_b[:, None, :], n_g)


def _cell(x: Float[Array, ""], lo: float, n: int):
    """Index and weight of x's cell on the uniform grid of n nodes on [lo, 1] (the clamp
    fires only for sin θ or cos φ an ulp outside [−1, 1])."""
    t = jnp.clip((x - lo) / (1.0 - lo) * (n - 1), 0.0, n - 1.0)
    i = jnp.minimum(jnp.floor(t), n - 2.0)
    return i.astype(jnp.int32), t - i


def dual_terms(
    tangent: Float[Array, " 3"],
    to_light: Float[Array, " 3"],
    to_eye: Float[Array, " 3"],
    count: Float[Array, ""],
    tables: DualTables,
    beta_m: Float[Array, ""],
    tilt: Float[Array, ""],
) -> tuple[Float[Array, "3 3"], Float[Array, "3 3"]]:
    """(direct, scattered) at one point, `[lobe (R, TT, TRT), RGB]`, as the lobes are
    (π·M·N, radiance per light colour), with `count` n fibres in front toward the light:

    - direct (the shadow's τ multiplies it, with the lobes): d_b·f_back, f_back =
      2·A_b·g(σ_b; x − Δ_b) (Zinke et al. 2008, eqs. 9–10: N_b = 2A_b/π), x = sin θ_L + sin θ_V;
    - scattered (τ does not multiply it): Ψ_s·(π·M^G_p·N^G_p + π·d_b·f_back^G),
      Ψ_s = d_f·(e^{−n(1−ā_f)} − e^{−n}), M^G_p the lobe's Gaussian widened by σ_f² =
      n·β̄_f², f_back^G's by σ_f² too (Zinke et al.'s F_scatter).

    f_back is split over the lobes by their shares a_b^p/ā_b (the lobe of the last, backward
    event), so the lobe weights scale it too; with weights 1 the sum is Zinke's term."""
    angles = fibre_angles(tangent, to_light, to_eye)
    i, w = _cell(angles.sin_l, -1.0, tables.a_f.shape[0])

    def at(table):
        return (1.0 - w) * table[i] + w * table[i + 1]

    a_f, var_f, a_back, shift_back, std_back, share = (
        at(t)
        for t in (
            tables.a_f,
            tables.var_f,
            tables.a_back,
            tables.shift_back,
            tables.std_back,
            tables.share_back,
        )
    )
    k, v = _cell(angles.cos_phi, -1.0, tables.n_g.shape[1])
    # Bilinear in (sin θ_L, cos φ) from the four nodes around the point: gathered one by
    # one, not as a column of every θ node first (`tables.n_g[:, k]`, 33 times the reads).
    n_g = (1.0 - v) * ((1.0 - w) * tables.n_g[i, k] + w * tables.n_g[i + 1, k]) + v * (
        (1.0 - w) * tables.n_g[i, k + 1] + w * tables.n_g[i + 1, k + 1]
    )  # [3 lobes, 3]

    x = angles.sin_l + angles.sin_v
    var_s = count * var_f  # σ_f² (RGB)
    back = 2.0 * a_back * gaussian(std_back, x - shift_back)
    back_s = 2.0 * a_back * gaussian(jnp.sqrt(std_back**2 + var_s), x - shift_back)
    widths = lobe_widths(beta_m)
    args = longitudinal_arguments(angles, tilt)
    m_g = jnp.stack([gaussian(jnp.sqrt(widths[p] ** 2 + var_s), args[p]) for p in range(3)])  # [3, 3]
    # e^{−n(1−ā_f)} − e^{−n} = e^{−n(1−ā_f)}·(−expm1(−n·ā_f)) ≥ 0: no cancellation at small
    # n, and both factors ≤ 1 (ā_f < 1), where e^{−n}·expm1(n·ā_f) overflowed to 0·∞ = NaN
    # for n·ā_f > 88 in float32 (709 in float64): Ω runs to the thousands deep in the hair.
    psi = DENSITY_FORWARD * jnp.exp(-count * (1.0 - a_f)) * -jnp.expm1(-count * a_f)
    direct = DENSITY_BACK * share * back[None, :]
    scattered = psi[None, :] * (jnp.pi * m_g * n_g + jnp.pi * DENSITY_BACK * share * back_s[None, :])
    return direct, scattered


def dual_terms_batched(tangent, to_light, to_eye, count, tables, beta_m, tilt):
    """`dual_terms` over points `[P, …]` (the tables shared)."""
    return jax.vmap(dual_terms, in_axes=(0, 0, 0, 0, None, None, None))(
        tangent, to_light, to_eye, count, tables, beta_m, tilt
    )
