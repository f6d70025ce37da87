"""The light side of the band: how much Ω may differ between the renderers at each point
(docs/model.md §7), and what that does to τ. The part that depends on the shadow method —
which boundaries a fragment or point may fall on either side of — is registered per
method name (`register_light_band`); `_opacity_maps.py` and `_exact.py` hold the built-in
ones."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

from .._constants import SHADOW_FILTER_RADIUS
from .._geometry._raster import ribbon_widths
from .._geometry._shadows import light_frame
from ._camera import end_band, segment_opacity

__all__ = [
    "WindowSums",
    "LightBand",
    "register_light_band",
    "light_band",
    "omega_uncertainty",
    "shadow_band",
    "transmittance_uncertainty",
]


@dataclasses.dataclass(frozen=True)
class LightBand:
    """A shadow method's boundaries. `terms(shadows, frame, frags, near_end, opacity, r)`
    returns `(uncertain, omega_at)`: per point (x, y texel, index) the bound on Ω from
    fragments near a boundary, and Ω itself from the fragments; `receivers(shadows, plan,
    frame, index)`: which of the receivers `index` (into `frame`, the light's frame with
    them, §13; `plan` the method's set-up) lie within rounding of a boundary of their own
    depth, where Ω jumps or the renderers pick a different slice (None: none do)."""

    terms: Callable
    receivers: Callable | None = None


_LIGHT_BANDS: dict[str, LightBand] = {}


def register_light_band(method: str, band: LightBand) -> None:
    """The band of shadow method `method` (hairjax/_geometry/_shadows/)."""
    _LIGHT_BANDS[method] = band


def light_band(shadows) -> LightBand:
    try:
        return _LIGHT_BANDS[shadows.method]
    except KeyError:
        raise NotImplementedError(
            f"no float32 disagreement band for shadows method {shadows.method!r}"
        ) from None


class WindowSums:
    """Σ of fragment values over a point's (2k + 1)² filter texels and a range of keys:
    fragments keyed by `key(texel, level)` (increasing in both, a texel's keys below the
    next texel's), summed by prefix sums over the sorted keys."""

    def __init__(self, key, texel, level, values, resolution: int):
        order = np.argsort(key(texel, level), kind="stable")
        self.key, self.r = key, resolution
        self.keys = key(texel, level)[order]
        self.prefix = np.r_[0.0, np.cumsum(values[order])]

    def __call__(self, tx, ty, lo, hi) -> np.ndarray:
        """Per point at texel (tx, ty): Σ values with lo ≤ level ≤ hi in its filter's texels
        (texels outside the map hold nothing)."""
        k, r = SHADOW_FILTER_RADIUS, self.r
        total = np.zeros(np.shape(tx))
        for oy in range(-k, k + 1):
            for ox in range(-k, k + 1):
                nx, ny = tx + ox, ty + oy
                valid = (nx >= 0) & (nx < r) & (ny >= 0) & (ny < r)
                total += self.texel(np.where(valid, ny * r + nx, -1), lo, hi)
        return total / (2 * k + 1) ** 2

    def texel(self, t, lo, hi) -> np.ndarray:
        """Σ values with lo ≤ level ≤ hi in texel `t` alone (−1: none, 0), unaveraged."""
        safe = np.maximum(t, 0)  # fires for t = −1: any texel, masked below
        sums = (
            self.prefix[np.searchsorted(self.keys, self.key(safe, hi), "right")]
            - self.prefix[np.searchsorted(self.keys, self.key(safe, lo), "left")]
        )
        return np.where(t >= 0, sums, 0.0)


def omega_uncertainty(scene) -> np.ndarray:
    """Per point (`float[P]`), a bound on |Ω_GL − Ω_JAX| from light-side discontinuities
    within rounding (docs/model.md §7); 0 where none applies. All 0 for shadows "none".

    - A light-space fragment of opacity a = α·coverage within rounding of a segment end
      may be drawn or not; one within SLICE_DELTA of plane m may count towards plane m or
      not; for `exact`, one within 16 float32 ulps of a point's own depth may count as
      nearer or not. Each moves the Ω of a point whose (2k + 1)² filter reads its texel by
      at most a / (2k + 1)², and only where it can count at all: a fragment in slice j adds
      to planes j + 1 … N, so to points in slices ≥ j (opacity maps), or to points behind
      it (exact); moving across plane m changes plane m only, so points in slices m − 1
      and m.
    - A point within rounding of a texel edge may filter the neighbouring texels instead:
      it adds how much Ω differs there, the largest over the neighbours it may land in.
    - Points the light does not see (behind a point light) get no shadow in either: 0.
    """
    s = scene.strands
    if not scene.shadows.casts:
        return np.zeros(s.num_points)
    r = scene.shadows.resolution
    segs = s.segments()
    frame = light_frame(s.points, segs, s.width, scene.light, r, s.width_units)
    ids = frame.drawable
    a, b = segs[ids, 0], segs[ids, 1]
    xy, z = frame.xy, frame.depth
    width = ribbon_widths(
        s.width[s.strand_of_point[a]], s.width_units, z[a], z[b], frame.view.focal, frame.view.perspective
    )
    frags, near_end = end_band(xy[a], xy[b], z[a], z[b], width, r, r, frame.view.perspective)
    opacity = segment_opacity(scene)[ids[frags.segment]] * frags.coverage
    # Clipped before the cast: unseen points of a light at the hair's centre lie at ~1e300.
    tx = np.floor(np.clip(xy[:, 0], -1, r)).astype(np.int64)
    ty = np.floor(np.clip(xy[:, 1], -1, r)).astype(np.int64)

    uncertain, omega_at = light_band(scene.shadows).terms(scene.shadows, frame, frags, near_end, opacity, r)
    everyone = np.arange(len(z))
    bound = uncertain(tx, ty, everyone)
    # A point within rounding of a texel edge may land in the neighbour (−1 or +1 per axis,
    # 0 where not near): GL's Ω then lies within that texel's bound of Ω there.
    frac = xy - np.floor(xy)
    side = np.where(frac < 1e-4, -1, np.where(1 - frac < 1e-4, 1, 0))
    edge = np.flatnonzero(frame.seen & (side != 0).any(axis=1))
    if edge.size:
        own = omega_at(tx[edge], ty[edge], edge)
        for sx, sy in ((1, 0), (0, 1), (1, 1)):
            x, y = tx[edge] + sx * side[edge, 0], ty[edge] + sy * side[edge, 1]
            there = uncertain(x, y, edge) + np.abs(omega_at(x, y, edge) - own)
            bound[edge] = np.maximum(bound[edge], there)
    bound[~frame.seen] = 0.0
    return bound


def shadow_band(scene) -> np.ndarray:
    """Points (`bool[P]`) whose Ω may depend on a light-side discontinuity within
    rounding (`omega_uncertainty` > 0). All False for shadows "none"."""
    return omega_uncertainty(scene) > 0


def transmittance_uncertainty(omega: np.ndarray, bound: np.ndarray) -> np.ndarray:
    """sup over κ > 0 of |exp(−κΩ) − exp(−κΩ')| for |Ω − Ω'| ≤ `bound`: how much τ may
    differ, whatever κ is (a fit does not know it). For a pair (a, a + d) the sup is at
    κ* = ln(1 + d/a)/d; for a given d it grows as a falls, so the worst pair lies below Ω
    (a = Ω − d). 1 where a ≤ 0 (κ → ∞ separates a shadow from none), 0 for d = 0, about
    d/(e·Ω) where d ≪ Ω."""
    d = np.asarray(bound, np.float64)
    a = np.asarray(omega, np.float64) - d
    out = np.ones_like(d)
    finite = np.isfinite(d) & (a > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        ka = np.where(finite, a * np.log1p(d / a) / d, 0.0)  # κ*·a
        kd = np.where(finite, np.log1p(d / a), 0.0)  # κ*·d
    out[finite] = (np.exp(-ka) * -np.expm1(-kd))[finite]
    out[d == 0] = 0.0
    return out
