"""The light band of opacity maps (docs/model.md §7): a fragment near a segment end may be
drawn or not, one near a slice plane may count towards it or not."""

from __future__ import annotations

import numpy as np

from ._light import LightBand, WindowSums, register_light_band
from ._tolerances import SLICE_DELTA


def opacity_map_terms(shadows, frame, frags, near_end, opacity, r):
    """`LightBand.terms` for `OpacityMaps`: N slices of the light's depth range."""
    z = frame.depth
    n = shadows.maps
    u = frame.slice_coordinate(frags.depth, n)
    near_plane = np.abs(u - np.round(u)) < SLICE_DELTA
    u_point = frame.slice_coordinate(z, n)
    plane = np.clip(np.floor(u_point), 0, n - 1)  # the point's slice i, f its weight
    f = np.clip(u_point - plane, 0.0, 1.0)

    def key(texel, level):  # levels 0 … N + 1
        return texel * (n + 2) + level

    # A fragment in slice j adds to planes j + 1 … N: to a point in slice i fully for
    # j < i, with weight f for j = i. Near an end: slice j, or j − 1 if also near a plane.
    ends = WindowSums(
        key, frags.pixel[near_end], np.clip(np.floor(u[near_end] - SLICE_DELTA), 0, n), opacity[near_end], r
    )
    # Near plane m: to plane m only, weighted f in slice m − 1 and 1 − f in slice m.
    planes = WindowSums(
        key, frags.pixel[near_plane], np.clip(np.round(u[near_plane]), 0, n), opacity[near_plane], r
    )
    every = WindowSums(key, frags.pixel, np.clip(np.floor(u), 0, n), opacity, r)

    def uncertain(x, y, i):
        i_, f_ = plane[i], f[i]
        return (
            ends(x, y, 0, i_ - 1)
            + f_ * ends(x, y, i_, i_)
            + f_ * planes(x, y, i_ + 1, i_ + 1)
            + (1 - f_) * planes(x, y, i_, i_)
        )

    def omega_at(x, y, i):
        # Ω̄(D_i) sums slices < i, Ω̄(D_{i+1}) slices ≤ i (slice N is dropped).
        return (1 - f[i]) * every(x, y, 0, plane[i] - 1) + f[i] * every(x, y, 0, plane[i])

    return uncertain, omega_at


def receivers_near_a_plane(shadows, plan, frame, index):
    """`LightBand.receivers` for `OpacityMaps`: within SLICE_DELTA of a plane."""
    u = frame.slice_coordinate(frame.depth[index], shadows.maps)
    return np.abs(u - np.round(u)) < SLICE_DELTA


register_light_band("opacity-maps", LightBand(opacity_map_terms, receivers=receivers_near_a_plane))
