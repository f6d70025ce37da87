"""The light band of exact Ω (docs/model.md §7): a fragment near a segment end may be
drawn or not, one within rounding of a point's own depth may count as nearer or not."""

from __future__ import annotations

import numpy as np

from ._light import LightBand, WindowSums, register_light_band


def exact_terms(shadows, frame, frags, near_end, opacity, r):
    """`LightBand.terms` for `ExactShadows`: depths strictly nearer than the point's own."""
    z = frame.depth
    # Ω counts fragments strictly nearer than the point; depths within dz are ties.
    # 16 float32 ulps of the largest depth: GL's perspective-correct depths from a
    # point light were measured 5 ulps off (point_light.toml, exact, 128²).
    dz = 16 * float(np.spacing(np.float32(np.abs(z[frame.seen]).max(initial=0.0))))

    # One key per (texel, depth): the texel plus the depth mapped into [0, ½].
    def key(texel, depth):
        return texel + 0.5 * np.clip((depth - frame.zmin + 2 * dz) / (frame.span + 4 * dz), 0.0, 1.0)

    ends = WindowSums(key, frags.pixel[near_end], frags.depth[near_end], opacity[near_end], r)
    every = WindowSums(key, frags.pixel, frags.depth, opacity, r)

    def uncertain(x, y, i):
        return ends(x, y, -np.inf, z[i] + dz) + every(x, y, z[i] - dz, z[i] + dz)

    def omega_at(x, y, i):
        return every(x, y, -np.inf, z[i])

    return uncertain, omega_at


register_light_band("exact", LightBand(exact_terms))
