"""The light band of deep opacity maps (docs/model.md §7; Yuksel & Keyser 2008): a
fragment near a segment end may be drawn or not, one near a layer boundary of its texel
may count towards it or not, a texel's first depth z₀ may be another fragment's when one
near a segment end is (or ties with) the nearest, and a point near the last boundary may
read the texel's total or not. With `lookup = "depth"` the same, texel by texel: each of
the point's 3 × 3 texels at its own k', f' from the point's depth behind that texel's z₀."""

from __future__ import annotations

import numpy as np

from .._constants import SHADOW_FILTER_RADIUS
from .._geometry._shadows import first_depths, layer_coordinate
from ._light import LightBand, WindowSums, register_light_band
from ._tolerances import SLICE_DELTA


def _depth_delta(frame) -> float:
    """16 float32 ulps of the largest light depth: GL's depths (fragments, points, z₀)
    are that close to JAX's (as `_exact.py`: perspective depths measured 5 ulps off)."""
    return 16 * float(np.spacing(np.float32(np.abs(frame.depth[frame.seen]).max(initial=0.0))))


def _layer_delta(shadows, frame) -> float:
    """ "Near a layer boundary", in layers: SLICE_DELTA, or the depth rounding of a
    fragment and of its texel's z₀ in layers when thin layers make that larger."""
    return max(SLICE_DELTA, 2 * _depth_delta(frame) * shadows.layers / shadows.depth_range(frame))


def deep_terms(shadows, frame, frags, near_end, opacity, r):
    """`LightBand.terms` for `DeepOpacityMaps`: K layers behind each texel's z₀."""
    n = shadows.layers
    depth_range = shadows.depth_range(frame)
    dz, du = _depth_delta(frame), _layer_delta(shadows, frame)
    # z₀ from the fragments both renderers draw, and from all that either may draw: where
    # one near an end lies in front (beyond rounding), the texel's z₀ is unsure and with it
    # every fragment's layer there.
    certain = first_depths(frags.pixel[~near_end], frags.depth[~near_end], r)
    nearest = first_depths(frags.pixel, frags.depth, r)
    unsure = nearest < certain - dz
    # Fires where only fragments near an end reach the texel: z₀ from them (unsure above).
    first = np.where(np.isfinite(certain), certain, nearest)
    u = layer_coordinate(frags.depth, first[frags.pixel], n, depth_range)
    # The clip fires below 0 for fragments in front of an unsure z₀, at K beyond the last boundary.
    level = np.clip(np.floor(u), 0, n)
    m = np.round(u)
    near_boundary = (np.abs(u - m) < du) & (m >= 1) & (m <= n)  # boundary 0 and the total never move

    def key(texel, lvl):  # levels 0 … K + 1
        return texel * (n + 2) + lvl

    # A fragment in slice j adds to boundaries j + 1 … K and the total: to a point with
    # lower boundary k fully for j < k, with weight f for j = k (beyond: k = K, f = 1).
    # Near an end: slice j, or j − 1 if also near a boundary.
    ends = WindowSums(
        key, frags.pixel[near_end], np.clip(np.floor(u[near_end] - du), 0, n), opacity[near_end], r
    )
    # Near boundary m: to boundary m only, weighted 1 − f at k = m and f at k = m − 1.
    bounds = WindowSums(key, frags.pixel[near_boundary], m[near_boundary], opacity[near_boundary], r)
    every = WindowSums(key, frags.pixel, level, opacity, r)
    moved = unsure[frags.pixel]
    shifted = WindowSums(key, frags.pixel[moved], np.zeros(int(moved.sum())), opacity[moved], r)
    z = frame.depth

    def weights(uu):
        """Lower boundary k and weight f at layer coordinate uu, as _deep.deep_points."""
        beyond = uu > n
        k = np.where(beyond, n, np.clip(np.floor(uu), 0, n - 1))
        return k, np.where(beyond, 1.0, np.clip(uu - k, 0.0, 1.0))

    if shadows.lookup == "depth":
        return _depth_lookup_terms(n, depth_range, du, z, first, unsure, weights, ends, bounds, every, r)

    def point(x, y, i):
        """Per point i placed in texel (x, y): its texel, whether it holds hair, k, f, u."""
        inside = (x >= 0) & (x < r) & (y >= 0) & (y < r)
        t = np.where(inside, y * r + x, 0)  # fires outside the map: any texel, masked
        hair = inside & np.isfinite(first[t])
        # Fires where there is no hair (z₀ = ∞): the point's own depth, u = 0, masked.
        uu = layer_coordinate(z[i], np.where(hair, first[t], z[i]), n, depth_range)
        k, f = weights(uu)
        return inside, t, hair, k, f, uu

    def uncertain(x, y, i):
        inside, t, hair, k, f, uu = point(x, y, i)
        own_unsure = inside & unsure[t]
        layered = (
            ends(x, y, 0, k - 1)
            + f * ends(x, y, k, k)
            + (1 - f) * bounds(x, y, k, k)
            + f * bounds(x, y, k + 1, k + 1)
            + shifted(x, y, 0, n + 1)
            # Near the last boundary: B̄_K or the total, which adds slice K.
            + np.where(np.abs(uu - n) < du, every(x, y, n, n), 0.0)
        )
        # An unsure z₀ of its own texel moves the point anywhere from 0 to the total.
        return np.where(hair | own_unsure, layered, 0.0) + np.where(own_unsure, every(x, y, 0, n), 0.0)

    def omega_at(x, y, i):
        _, _, hair, k, f, _ = point(x, y, i)
        # Boundary k sums slices < k, boundary k + 1 (the total beyond) slices ≤ k.
        return np.where(hair, (1 - f) * every(x, y, 0, k - 1) + f * every(x, y, 0, k), 0.0)

    return uncertain, omega_at


def _depth_lookup_terms(n, depth_range, du, z, first, unsure, weights, ends, bounds, every, r):
    """`deep_terms` for `lookup = "depth"`: the layer lookup's terms per filter texel t',
    each at the point's own k', f' in t' and /9; a texel whose z₀ is unsure may hold
    anything from 0 to its total."""
    side = (2 * SHADOW_FILTER_RADIUS + 1) ** 2

    def over_texels(x, y, i, value):
        """(1/9) Σ over the point's filter texels t' of value(t', hair, k', f', u')."""
        total = np.zeros(np.shape(x))
        offsets = range(-SHADOW_FILTER_RADIUS, SHADOW_FILTER_RADIUS + 1)
        for oy in offsets:
            for ox in offsets:
                nx, ny = x + ox, y + oy
                valid = (nx >= 0) & (nx < r) & (ny >= 0) & (ny < r)
                t = np.where(valid, ny * r + nx, -1)
                z0 = first[np.maximum(t, 0)]  # fires outside the map: any texel, masked
                hair = valid & np.isfinite(z0)
                # Fires where there is no hair (z₀ = ∞): the point's own depth, u' = 0, masked.
                uu = layer_coordinate(z[i], np.where(hair, z0, z[i]), n, depth_range)
                k, f = weights(uu)
                total += value(t, valid & unsure[np.maximum(t, 0)], hair, k, f, uu)
        return total / side

    def uncertain_in(t, moved, hair, k, f, uu):
        layered = (
            ends.texel(t, 0, k - 1)
            + f * ends.texel(t, k, k)
            + (1 - f) * bounds.texel(t, k, k)
            + f * bounds.texel(t, k + 1, k + 1)
            # Near the last boundary: Ω_K or the total, which adds slice K.
            + np.where(np.abs(uu - n) < du, every.texel(t, n, n), 0.0)
        )
        # An unsure z₀ moves this texel's value anywhere from 0 to its total.
        return np.where(moved, every.texel(t, 0, n), np.where(hair, layered, 0.0))

    def omega_in(t, moved, hair, k, f, uu):
        # Boundary k sums slices < k, boundary k + 1 (the total beyond) slices ≤ k.
        return np.where(hair, (1 - f) * every.texel(t, 0, k - 1) + f * every.texel(t, 0, k), 0.0)

    def uncertain(x, y, i):
        return over_texels(x, y, i, uncertain_in)

    def omega_at(x, y, i):
        return over_texels(x, y, i, omega_in)

    return uncertain, omega_at


def receivers_near_the_last_boundary(shadows, plan, frame, index):
    """`LightBand.receivers` for `DeepOpacityMaps`: within rounding of z₀ + KΔ of their
    texel (JAX's z₀, `plan.first_depth`; with `lookup = "depth"` any of their 3 × 3
    texels'), where Ω jumps from B̄_K to the total. Elsewhere Ω is continuous in the
    receiver's depth."""
    texel = plan.texel[index]
    depth = frame.depth[index]
    if texel.ndim == 2:  # lookup "depth": [P, 9], each texel's own z₀
        depth = np.broadcast_to(depth[:, None], texel.shape)
    z0 = plan.first_depth[np.maximum(texel, 0)]  # fires outside or without hair: masked below
    u = layer_coordinate(depth, np.where(texel >= 0, z0, depth), shadows.layers, shadows.depth_range(frame))
    near = (texel >= 0) & (np.abs(u - shadows.layers) < _layer_delta(shadows, frame))
    return near.any(axis=1) if near.ndim == 2 else near


register_light_band("deep", LightBand(deep_terms, receivers=receivers_near_the_last_boundary))
