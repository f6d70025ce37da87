"""The physically based reference's settings (docs/reference.md): the fibres' BSDF and the
path tracer's depth and samples, as a scene file's `[reference]` table gives them.

`hairjax reference` renders the scene's strands as fibres with Chiang et al. 2016's hair
BSDF (Mitsuba 3's `hair` plugin); nothing here imports Mitsuba. The defaults are the
plugin's own (brown hair: eumelanin 1.3, pheomelanin 0.2; roughness 0.3 and 0.3; cuticle
tilt 2°; η 1.55), so an empty table is Mitsuba's default hair.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

from .._errors import SceneError
from .._values._light import RGBInput, rgb
from ._table import Table, given

__all__ = [
    "ReferenceSettings",
    "read_reference",
    "REFERENCE_KEYS",
    "DEFAULT_EUMELANIN",
    "DEFAULT_PHEOMELANIN",
]

# Mitsuba's `hair` plugin's defaults: brown hair (pbrt-v3's and Chiang et al.'s example).
DEFAULT_EUMELANIN = 1.3
DEFAULT_PHEOMELANIN = 0.2


def _number(key: str, value, lo: float, hi: float, *, lo_open: bool = False) -> float:
    ok = (
        isinstance(value, int | float)
        and not isinstance(value, bool)
        and math.isfinite(value)
        and (value > lo if lo_open else value >= lo)
        and value <= hi
    )
    if not ok:
        bounds = f"in {'(' if lo_open else '['}{lo:g}, {hi:g}]" if math.isfinite(hi) else f">= {lo:g}"
        raise SceneError(f"reference.{key} must be a number {bounds}, got {value!r}")
    return float(value)


def _integer(key: str, value, lo: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < lo:
        raise SceneError(f"reference.{key} must be an integer >= {lo}, got {value!r}")
    return int(value)


@dataclasses.dataclass(frozen=True)
class ReferenceSettings:
    """The fibres and the path tracer of `hairjax.reference_image` (docs/reference.md).

    **Fields:**

    - `eumelanin`, `pheomelanin`: pigment concentrations (≥ 0), which give the fibres'
      absorption (d'Eon et al. 2011, as Chiang et al. 2016 and Mitsuba use them); default
      1.3 and 0.2 (brown). Blonde is about 0.3, black 8.
    - `sigma_a`: the absorption coefficient as RGB (≥ 0) instead of the pigments, in
      Mitsuba's units (relative to the fibre's radius, so independent of its world size).
      Excludes `eumelanin` and `pheomelanin`; after construction exactly one of the two
      ways is set (the pigments hold None when `sigma_a` is given).
    - `longitudinal_roughness`, `azimuthal_roughness`: Chiang's β_m and β_n, in (0, 1].
    - `scale_tilt`: the cuticle scales' tilt α, degrees, in [−45, 45]: it shifts the
      highlights along the fibre.
    - `eta`: the fibre's index of refraction, in [1, 3].
    - `max_depth`: the longest path (Mitsuba's `path` integrator), ≥ 2: 2 is direct light
      only, more adds the light scattered between fibres (1 would show light sources only,
      and a directional or point light is never seen). Default 16.
    - `spp`: samples per pixel (`hairjax reference --spp` overrides it), rounded up to the
      stratified sampler's grid (`_reference._mitsuba_scene.sample_count`). Default 64.
    """

    eumelanin: float | int | None = None
    pheomelanin: float | int | None = None
    sigma_a: RGBInput | None = None
    longitudinal_roughness: float | int = 0.3
    azimuthal_roughness: float | int = 0.3
    scale_tilt: float | int = 2.0
    eta: float | int = 1.55
    max_depth: int = 16
    spp: int = 64

    def __post_init__(self):
        if self.sigma_a is not None:
            if self.eumelanin is not None or self.pheomelanin is not None:
                raise SceneError(
                    "reference.sigma_a excludes reference.eumelanin and reference.pheomelanin: "
                    "give the absorption or the pigments, not both"
                )
            object.__setattr__(self, "sigma_a", rgb("reference.sigma_a", self.sigma_a))
        else:
            for key, default in (("eumelanin", DEFAULT_EUMELANIN), ("pheomelanin", DEFAULT_PHEOMELANIN)):
                value = getattr(self, key)
                value = default if value is None else _number(key, value, 0.0, math.inf)
                object.__setattr__(self, key, value)
        for key in ("longitudinal_roughness", "azimuthal_roughness"):
            object.__setattr__(self, key, _number(key, getattr(self, key), 0.0, 1.0, lo_open=True))
        object.__setattr__(self, "scale_tilt", _number("scale_tilt", self.scale_tilt, -45.0, 45.0))
        object.__setattr__(self, "eta", _number("eta", self.eta, 1.0, 3.0))
        object.__setattr__(self, "max_depth", _integer("max_depth", self.max_depth, 2))
        object.__setattr__(self, "spp", _integer("spp", self.spp, 1))


REFERENCE_KEYS = tuple(f.name for f in dataclasses.fields(ReferenceSettings))


def read_reference(table: Table) -> dict[str, Any]:
    """[reference]: `ReferenceSettings`' keyword arguments, types checked here (ranges are
    the dataclass's)."""
    return given(
        eumelanin=table.number("eumelanin"),
        pheomelanin=table.number("pheomelanin"),
        sigma_a=table.rgb("sigma_a", scalar=True),
        longitudinal_roughness=table.number("longitudinal_roughness"),
        azimuthal_roughness=table.number("azimuthal_roughness"),
        scale_tilt=table.number("scale_tilt"),
        eta=table.number("eta"),
        max_depth=table.integer("max_depth"),
        spp=table.integer("spp"),
    )
