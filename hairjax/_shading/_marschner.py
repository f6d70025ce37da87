"""The `marschner` shading model: Karis's R/TT/TRT approximation of a Marschner-family
fibre, coloured by absorption from melanin as Mitsuba 3's `hair` BSDF defines it
(docs/model.md §19). The per-point lobes are in `_marschner_lobes.py`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._constants import EUMELANIN_SIGMA_A, PHEOMELANIN_SIGMA_A
from .._errors import SceneError
from ._dual_scattering import DENSITY_BACK, DENSITY_FORWARD, dual_tables, dual_terms_batched
from ._marschner_lobes import TILT_MULTIPLES, Azimuthal, lobe_widths, marschner_lobes
from ._model import (
    AbstractShadingModel,
    Plateau,
    Reflectance,
    RGBLike,
    ShadingPoints,
    check_params,
    register_shading_model,
    rgb_param,
    rgb_uniform,
    scalar_param,
    values_repr,
)
from ._transforms import IDENTITY, LOG, LOGIT, SOFTPLUS

__all__ = ["MarschnerParams", "Marschner", "absorption", "MULTIPLE_SCATTERING"]


class MarschnerParams(eqx.Module):
    """The differentiable parameters of the `marschner` model (a pytree of arrays).

    **Fields:**
    - `eumelanin`, `pheomelanin`: pigment concentrations ≥ 0 (Mitsuba's `hair` BSDF:
      0.3 blonde, 1.3 brown, 8 black); `sigma_a`: RGB absorption per unit fibre radius
      added to the pigments' (0 by default; a scene file that gives `sigma_a` and no
      pigment means σ_a alone, as Mitsuba's `sigma_a`). The fibre's σ_a is `absorption(params)`.
    - `longitudinal_roughness`: β_m in (0, 1], as Mitsuba's; `azimuthal_roughness`: β_n in
      (0, 1], as Mitsuba's, read by `azimuthal = "chiang"` only (Karis's azimuthal
      approximations fix their own spread); `tilt`: the cuticle scales'
      angle α in degrees (Mitsuba's `scale_tilt`, 2 by default).
    - `weight_r`, `weight_tt`, `weight_trt`: RGB weights of the three lobes (1: the
      physical fibre; other values are art direction); `ambient`: an RGB ambient light
      term; `kappa`: κ in τ = exp(−κΩ) (§7).

    Concrete values are checked at construction (`SceneError` naming the field)."""

    eumelanin: Float[Array, ""]
    pheomelanin: Float[Array, ""]
    sigma_a: Float[Array, " 3"]
    longitudinal_roughness: Float[Array, ""]
    azimuthal_roughness: Float[Array, ""]
    tilt: Float[Array, ""]
    weight_r: Float[Array, " 3"]
    weight_tt: Float[Array, " 3"]
    weight_trt: Float[Array, " 3"]
    ambient: Float[Array, " 3"]
    kappa: Float[Array, ""]

    def __init__(
        self,
        eumelanin: ArrayLike = 1.3,
        pheomelanin: ArrayLike = 0.2,
        sigma_a: RGBLike = 0.0,
        longitudinal_roughness: ArrayLike = 0.3,
        azimuthal_roughness: ArrayLike = 0.3,
        tilt: ArrayLike = 2.0,
        weight_r: RGBLike = 1.0,
        weight_tt: RGBLike = 1.0,
        weight_trt: RGBLike = 1.0,
        ambient: RGBLike = 0.0,
        kappa: ArrayLike = 1.0,
    ):
        self.eumelanin = scalar_param(eumelanin)
        self.pheomelanin = scalar_param(pheomelanin)
        self.sigma_a = rgb_param(sigma_a)
        self.longitudinal_roughness = scalar_param(longitudinal_roughness)
        self.azimuthal_roughness = scalar_param(azimuthal_roughness)
        self.tilt = scalar_param(tilt)
        self.weight_r = rgb_param(weight_r)
        self.weight_tt = rgb_param(weight_tt)
        self.weight_trt = rgb_param(weight_trt)
        self.ambient = rgb_param(ambient)
        self.kappa = scalar_param(kappa)

    def __check_init__(self):
        check_params(
            self,
            colors=("sigma_a", "weight_r", "weight_tt", "weight_trt", "ambient"),
            non_negative=("eumelanin", "pheomelanin", "kappa"),
            positive=("longitudinal_roughness", "azimuthal_roughness"),
            finite=("tilt",),
        )
        for name in ("longitudinal_roughness", "azimuthal_roughness"):
            beta = getattr(self, name)
            if not isinstance(beta, jax.core.Tracer) and float(np.asarray(beta)) > 1.0:
                raise SceneError(f"shading.{name} must be in (0, 1], got {float(beta):g}")

    def __repr__(self) -> str:
        return values_repr(self)


def absorption(params: MarschnerParams) -> Float[Array, " 3"]:
    """The fibre's σ_a per unit radius: eumelanin·σ_eu + pheomelanin·σ_pheo + sigma_a
    (Mitsuba 3's `hair` BSDF in RGB, d'Eon et al. 2011's pigment coefficients)."""
    eu = jnp.asarray(EUMELANIN_SIGMA_A, dtype=params.sigma_a.dtype)
    pheo = jnp.asarray(PHEOMELANIN_SIGMA_A, dtype=params.sigma_a.dtype)
    return params.eumelanin * eu + params.pheomelanin * pheo + params.sigma_a


_LOBE_GAINS = ("weight_r", "weight_tt", "weight_trt")
# `multiple_scattering`: single scattering alone, or with Zinke et al. 2008's dual
# scattering (docs/model.md §19, `_dual_scattering.py`).
MULTIPLE_SCATTERING = ("none", "dual")
# The ways N_p is computed (`Marschner.azimuthal`, docs/model.md §19).
AZIMUTHAL = ("karis", "chiang")


@register_shading_model
class Marschner(AbstractShadingModel):
    """Karis's R/TT/TRT approximation of a Marschner fibre (docs/model.md §19): the colour
    at a point is ambient + τ·V·light·(w_R·R + w_TT·TT + w_TRT·TRT), each lobe π·M_p·N_p
    with σ_a from melanin. The strands' own colour is not read (as in the reference: a
    fibre's colour is its absorption).

    `multiple_scattering` (static): "none", or "dual" for light scattered between fibres
    (Zinke et al. 2008): the lobes' weights scale it too, so the colour stays linear in
    them; its forward-scattered part is not shadowed by τ (`Reflectance.scattered`)."""

    params: MarschnerParams = eqx.field(default_factory=MarschnerParams)
    multiple_scattering: str = eqx.field(static=True, default="none")
    # How N_p is computed: "karis" (Karis 2016's closed forms) or "chiang" (Chiang et al.
    # 2016's far field, `azimuthal_samples` quadrature nodes across the fibre).
    azimuthal: str = eqx.field(static=True, default="karis")
    azimuthal_samples: int = eqx.field(static=True, default=64)

    name: ClassVar[str] = "marschner"
    params_type: ClassVar[type] = MarschnerParams
    table_keys: ClassVar[tuple[str, ...]] = (
        "eumelanin",
        "pheomelanin",
        "sigma_a",
        "longitudinal_roughness",
        "azimuthal_roughness",
        "tilt",
        "weight_r",
        "weight_tt",
        "weight_trt",
        "ambient",
        "kappa",
        "multiple_scattering",
        "azimuthal",
        "azimuthal_samples",
    )
    # azimuthal_roughness is fitted where named, with azimuthal = "chiang" (it reaches
    # nothing with "karis").
    fittable: ClassVar[tuple[str, ...]] = (
        *_LOBE_GAINS,
        "eumelanin",
        "pheomelanin",
        "longitudinal_roughness",
        "tilt",
        "kappa",
    )
    searched: ClassVar[Mapping] = {
        "eumelanin": SOFTPLUS,
        "pheomelanin": SOFTPLUS,
        "sigma_a": LOG,
        "longitudinal_roughness": LOGIT,
        "azimuthal_roughness": LOGIT,
        "tilt": IDENTITY,
        "kappa": LOG,
    }
    # The lobe weights are fitted as one grey value each unless the caller says otherwise:
    # in RGB they would take the colour from the absorption, which is what a fit is to find.
    grey: ClassVar[tuple[str, ...]] = _LOBE_GAINS
    # With the transmitted lobes' weight solved to 0 the pigments have no effect (R carries
    # no colour): the fit then tries Mitsuba's example hair colours (blonde 0.3, brown 1.3,
    # black 8; pheomelanin 0 to the red 1.2), and a small value where 0 is meant.
    plateaus: ClassVar[tuple[Plateau, ...]] = (
        Plateau("eumelanin", (0.01, 0.1, 0.3, 1.3, 3.0, 8.0), gain="weight_tt"),
        Plateau("pheomelanin", (0.01, 0.2, 0.5, 1.2, 3.0), gain="weight_tt"),
    )
    # Slider ranges (hj.explore): Mitsuba's pigment examples and roughness range, a tilt
    # of up to ±10° (human hair: 2–4°, Marschner et al. 2003), weights around 1.
    ranges: ClassVar[Mapping[str, tuple[float, float]]] = {
        "eumelanin": (0.0, 10.0),
        "pheomelanin": (0.0, 5.0),
        "sigma_a": (0.0, 10.0),
        "longitudinal_roughness": (0.02, 1.0),
        "azimuthal_roughness": (0.02, 1.0),
        "tilt": (-10.0, 10.0),
        "weight_r": (0.0, 4.0),
        "weight_tt": (0.0, 4.0),
        "weight_trt": (0.0, 4.0),
    }
    gl_id: ClassVar[int | None] = 4

    def __check_init__(self):
        if self.azimuthal not in AZIMUTHAL:
            raise SceneError(
                f"shading.azimuthal must be one of {', '.join(AZIMUTHAL)}, got {self.azimuthal!r}"
            )
        if not 2 <= self.azimuthal_samples <= 4096:
            raise SceneError(f"shading.azimuthal_samples must be in [2, 4096], got {self.azimuthal_samples}")
        if self.multiple_scattering not in MULTIPLE_SCATTERING:
            raise SceneError(
                f"shading.multiple_scattering must be one of {', '.join(MULTIPLE_SCATTERING)}, "
                f"got {self.multiple_scattering!r}"
            )
        if self.multiple_scattering == "dual" and self.azimuthal != "karis":
            # The dual-scattering tables integrate Karis's azimuthal lobes (`azimuthal_lobes`).
            raise SceneError('shading.multiple_scattering = "dual" needs shading.azimuthal = "karis"')

    def reflectance(self, points: ShadingPoints, params: MarschnerParams) -> Reflectance:
        sigma_a, beta, tilt = absorption(params), params.longitudinal_roughness, params.tilt
        azimuthal = None
        if self.azimuthal == "chiang":
            azimuthal = Azimuthal(params.azimuthal_roughness, self.azimuthal_samples)
        lobes = jax.vmap(
            lambda t, light, eye: marschner_lobes(t, light, eye, sigma_a, beta, tilt, azimuthal)
        )(points.tangent, points.to_light, points.to_eye)
        r, tt, trt = lobes
        shape = points.base_color.shape
        lit = {"weight_r": jnp.broadcast_to(r[:, None], shape), "weight_tt": tt, "weight_trt": trt}
        ambient = {"ambient": jnp.ones(shape, points.base_color.dtype)}
        if self.multiple_scattering != "dual":
            return Reflectance(ambient=ambient, lit=lit)
        # n = κΩ fibres in front (docs/model.md §19): τ = e^{−κΩ} is the chance of crossing
        # none when the crossings are Poisson with that mean; no shadows: none in front.
        count = jnp.zeros(shape[:1], points.base_color.dtype)
        if points.omega is not None:
            count = params.kappa * points.omega
        tables = dual_tables(sigma_a, beta, tilt)
        direct, scattered = dual_terms_batched(
            points.tangent, points.to_light, points.to_eye, count, tables, beta, tilt
        )
        return Reflectance(
            ambient=ambient,
            lit={g: lit[g] + direct[:, i] for i, g in enumerate(_LOBE_GAINS)},
            scattered={g: scattered[:, i] for i, g in enumerate(_LOBE_GAINS)},
        )

    def gl_unsupported(self) -> str | None:
        # The camera shader has Karis's closed forms only: refused rather than drawing
        # another model than the JAX one.
        if self.azimuthal != "karis":
            return 'the GL renderer has no shading.azimuthal = "chiang" (JAX only); use "karis"'
        return None

    def gl_uniforms(self, params: MarschnerParams) -> dict:
        """The `Marschner` struct of model.glsl: what depends on the parameters alone is
        computed here by the JAX functions the lobes use (σ_a, the Gaussians' widths, each
        lobe's tilt kα in radians), so GLSL repeats no formula of the parameters."""
        tilts = np.asarray(TILT_MULTIPLES) * np.deg2rad(float(params.tilt))
        return {
            "shading.ambient": rgb_uniform(params.ambient),
            "marschner.sigma_a": rgb_uniform(absorption(params)),
            "marschner.widths": rgb_uniform(lobe_widths(params.longitudinal_roughness)),
            "marschner.tilts": tuple(float(t) for t in tilts),
            "marschner.weight_r": rgb_uniform(params.weight_r),
            "marschner.weight_tt": rgb_uniform(params.weight_tt),
            "marschner.weight_trt": rgb_uniform(params.weight_trt),
            "marschner.dual": self.multiple_scattering == "dual",
            "marschner.density_forward": DENSITY_FORWARD,
            "marschner.density_back": DENSITY_BACK,
        }

    def gl_table(self, params: MarschnerParams) -> np.ndarray | None:
        """Dual scattering's tables (`dual_tables`, computed by the JAX code) as the
        `[rows, J, 3]` texels model.glsl's dual_terms reads (None without dual scattering):
        rows ā_f, β̄_f², A_b, Δ_b, σ_b, the shares of R, TT, TRT, then N^G_p at each cos φ
        node k and lobe p (row 8 + 3k + p), columns the light's sin θ nodes."""
        if self.multiple_scattering != "dual":
            return None
        t = dual_tables(absorption(params), params.longitudinal_roughness, params.tilt)
        rows = [t.a_f, t.var_f, t.a_back, t.shift_back, t.std_back]
        rows += [t.share_back[:, p] for p in range(3)]
        rows += [t.n_g[:, k, p] for k in range(t.n_g.shape[1]) for p in range(3)]
        return np.stack([np.asarray(r, dtype=np.float64) for r in rows])

    @classmethod
    def from_table(cls, table) -> Marschner:
        given = table.given(
            eumelanin=table.number("eumelanin", lo=0),
            pheomelanin=table.number("pheomelanin", lo=0),
            sigma_a=table.rgb("sigma_a", scalar=True),
            longitudinal_roughness=table.number("longitudinal_roughness", lo=0, hi=1, lo_open=True),
            azimuthal_roughness=table.number("azimuthal_roughness", lo=0, hi=1, lo_open=True),
            tilt=table.number("tilt"),
            weight_r=table.rgb("weight_r", scalar=True),
            weight_tt=table.rgb("weight_tt", scalar=True),
            weight_trt=table.rgb("weight_trt", scalar=True),
            ambient=table.rgb("ambient", scalar=True),
            kappa=table.number("kappa", lo=0),
        )
        if "sigma_a" in given:
            # σ_a given directly: the pigments add to it only where given too (0 otherwise,
            # not the brown default), so `sigma_a` alone means the same as in Mitsuba.
            given.setdefault("eumelanin", 0.0)
            given.setdefault("pheomelanin", 0.0)
        options = table.given(
            azimuthal=table.choice("azimuthal", AZIMUTHAL),
            azimuthal_samples=table.integer("azimuthal_samples", lo=2),
            multiple_scattering=table.choice("multiple_scattering", MULTIPLE_SCATTERING),
        )
        return cls(params=MarschnerParams(**given), **options)

    def table(self) -> dict:
        return {
            **super().table(),
            "azimuthal": self.azimuthal,
            "azimuthal_samples": self.azimuthal_samples,
            "multiple_scattering": self.multiple_scattering,
        }
