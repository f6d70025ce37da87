"""Procedural hair: Wenzel's fur ball, a scalp of strands bending under gravity, and hair
combed over a head in layers (the guide curves of hair patches)."""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from .._geometry._capacity import check_generated
from .._values._strands import Strands

__all__ = ["furball", "scalp", "combed"]


@runtime_checkable
class _NormalSource(Protocol):
    """What `_unit_vectors` draws from: a `np.random.Generator`, or any object with its
    `normal(size=...)` (the tests' stub)."""

    def normal(self, *, size: tuple[int, int]) -> np.ndarray: ...


def _unit_vectors(rng: _NormalSource, n: int) -> np.ndarray:
    v = rng.normal(size=(n, 3))
    norm = np.linalg.norm(v, axis=1, keepdims=True)
    # Fires with probability ~0 (a normal draw of exactly 0); such a hair points along +y.
    return np.where(norm > 0, v / np.where(norm > 0, norm, 1.0), [0.0, 1.0, 0.0])


def _grow(roots, directions, lengths, points, gravity, inertia) -> np.ndarray:
    """wenzel-2002's joint loop for all hairs at once: `float64[n, points, 3]`."""
    gravity = np.asarray(gravity, dtype=np.float64)
    inertia = np.broadcast_to(np.asarray(inertia, dtype=np.float64), directions.shape)
    out = np.empty((len(roots), points, 3))
    pos, cur = roots.copy(), directions.copy()
    out[:, 0] = pos
    for j in range(1, points):
        tmp = cur + gravity + inertia
        norm = np.linalg.norm(tmp, axis=1, keepdims=True)
        # Fires when gravity + inertia exactly cancel the direction: keep the old direction.
        tmp = np.where(norm > 0, tmp / np.where(norm > 0, norm, 1.0), cur)
        pos = pos + tmp * lengths[:, None]
        cur = tmp
        out[:, j] = pos
    return out


def furball(
    strands: int = 20000,
    points: int = 16,
    seed: int = 0,
    length: float = 1.0,
    gravity=(0.0, -0.08, 0.0),
    inertia=(0.0, 0.0, 0.0),
    length_jitter: float = 0.2,
    alpha: float = 0.5,
    width: float = 1.0,
) -> Strands:
    """wenzel-2002's fur ball: hairs from the origin in random unit directions.

    Each hair has `points` joints; each step's direction is
    normalise(current + gravity + inertia), and the position advances by that direction
    times the hair's segment length `length / (points - 1) × U(1 ± length_jitter)`.
    Deterministic for a `seed`.
    """
    if strands < 1 or points < 2:
        raise ValueError("furball needs at least 1 strand of at least 2 points")
    check_generated(strands, points)
    rng = np.random.default_rng(seed)
    directions = _unit_vectors(rng, strands)
    seg = length / (points - 1) * rng.uniform(1 - length_jitter, 1 + length_jitter, strands)
    pts = _grow(np.zeros((strands, 3)), directions, seg, points, gravity, inertia)
    offsets = np.arange(strands + 1) * points
    return Strands(pts.reshape(-1, 3), offsets, alpha, width)


def scalp(
    strands: int = 20000,
    points: int = 16,
    seed: int = 0,
    length: float = 1.0,
    gravity=(0.0, -0.15, 0.0),
    radius: float = 0.5,
    coverage: float = 0.6,
    length_jitter: float = 0.2,
    alpha: float = 0.5,
    width: float = 1.0,
) -> Strands:
    """Strands rooted on the upper part of a sphere of `radius`, growing along the normal
    and bending under `gravity` with the fur ball's joint rule.

    `coverage` is the fraction of the sphere's height, from the top, that carries roots.
    """
    if strands < 1 or points < 2:
        raise ValueError("scalp needs at least 1 strand of at least 2 points")
    check_generated(strands, points)
    if not 0 < coverage <= 1:
        raise ValueError("coverage must be in (0, 1]")
    rng = np.random.default_rng(seed)
    # Uniform on the spherical cap y ∈ [1 - 2·coverage, 1] (Archimedes: uniform in y).
    y = rng.uniform(1 - 2 * coverage, 1, strands)
    phi = rng.uniform(0, 2 * np.pi, strands)
    r = np.sqrt(np.clip(1 - y * y, 0, None))  # never fires: |y| ≤ 1 gives fl(y²) ≤ 1
    normals = np.stack([r * np.cos(phi), y, r * np.sin(phi)], axis=1)
    seg = length / (points - 1) * rng.uniform(1 - length_jitter, 1 + length_jitter, strands)
    pts = _grow(normals * radius, normals, seg, points, gravity, (0.0, 0.0, 0.0))
    offsets = np.arange(strands + 1) * points
    return Strands(pts.reshape(-1, 3), offsets, alpha, width)


def combed(
    strands: int = 72,
    points: int = 16,
    seed: int = 0,
    length: float = 2.2,
    radius: float = 1.0,
    layers: int = 3,
    gap: float = 0.06,
    fringe: float = 1.0,
    face: float = 0.9,
    length_jitter: float = 0.1,
    alpha: float = 0.5,
    width: float = 1.0,
) -> Strands:
    """Hair combed down over a head, the sphere of `radius` at the origin, in `layers`
    shells: the guide curves of scheuermann-2004 slide 5's "several layers of patches"
    (docs/model.md §18).

    Strand i lies in layer l = i mod `layers`, on the sphere of radius
    `radius`·(1 + `gap`·(l + 1)) (layer 0 innermost). It starts near the crown (polar angle
    U(0.1, 0.2) rad), runs down its meridian to the equator and then straight down (−y),
    `length`·U(1 ± `length_jitter`) long in all; over the face (azimuth within `face` rad
    of +z) it stops at polar angle `fringe` rad. Each layer's azimuths are evenly spaced,
    turned by half a step against the layer below, plus U(±¼ step). Points are evenly
    spaced along the curve. Deterministic for a `seed`.
    """
    if strands < 1 or points < 2 or layers < 1:
        raise ValueError("combed needs at least 1 strand of at least 2 points and 1 layer")
    check_generated(strands, points)
    rng = np.random.default_rng(seed)
    layer = np.arange(strands) % layers
    rank = np.arange(strands) // layers  # position within its layer
    per_layer = np.bincount(layer, minlength=layers)[layer]
    step = 2 * np.pi / per_layer
    phi = step * (rank + 0.5 * (layer % 2) + rng.uniform(-0.25, 0.25, strands))
    r = radius * (1 + gap * (layer + 1))
    theta0 = rng.uniform(0.1, 0.2, strands)
    total = length * rng.uniform(1 - length_jitter, 1 + length_jitter, strands)
    over_face = np.abs(np.angle(np.exp(1j * phi))) < face  # azimuth wrapped to (−π, π]
    total = np.where(over_face, np.minimum(total, r * (fringe - theta0)), total)
    s = total[:, None] * np.linspace(0.0, 1.0, points)[None, :]  # arc length, [n, points]
    on_head = r[:, None] * (np.pi / 2 - theta0[:, None])  # arc length to the equator
    theta = theta0[:, None] + np.minimum(s, on_head) / r[:, None]
    drop = np.maximum(s - on_head, 0.0)  # straight down below the equator
    side = np.stack([np.sin(phi), np.zeros(strands), np.cos(phi)], axis=1)  # azimuth φ, +z at 0
    pts = r[:, None, None] * (np.sin(theta)[..., None] * side[:, None, :])
    pts[..., 1] = r[:, None] * np.cos(theta) - drop
    offsets = np.arange(strands + 1) * points
    return Strands(pts.reshape(-1, 3), offsets, alpha, width)
