"""Procedural hair: Wenzel's fur ball and a scalp of strands bending under gravity."""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from ._strands import Strands

__all__ = ["furball", "scalp"]


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
