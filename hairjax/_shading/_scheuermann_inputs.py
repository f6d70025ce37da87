"""The Scheuermann model's per-point inputs, made in NumPy from the geometry alone
(scheuermann-2004 slides 9–13, docs/model.md §17): strand normals, the shift texture and
noise mask, and base/alpha/occlusion textures along the strand, with the hair's own
ambient occlusion. Computed only for scenes that use the model.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import equinox as eqx
import numpy as np
from jaxtyping import ArrayLike, Float

from .._errors import SceneError
from .._geometry._ordering import hair_centre
from .._geometry._shadows import ExactShadows, ShadowInputs
from .._values._light import Light, Vec3Like

__all__ = [
    "ScheuermannMaps",
    "ScheuermannPoints",
    "strand_normals",
    "strand_position",
    "scheuermann_inputs",
    "segment_alpha",
    "hair_occlusion",
    "sphere_directions",
    "HAIR_OCCLUSION_RESOLUTION",
    "HAIR_OCCLUSION_DIRECTIONS",
]

# The light rasters of `hair_occlusion`: a strand of width w covers w texels of this many
# across the hair, i.e. occludes as in a render of the hair at this resolution. Coarse on
# purpose: ambient occlusion is the hair's large-scale density, not single strands.
HAIR_OCCLUSION_RESOLUTION = 64
# Directions `hair_occlusion` averages over: 16 on the sphere resolve the hair's shape (its
# inside vs. its outside) at ~1/4 of the set-up time of a 64-map opacity-map shadow.
HAIR_OCCLUSION_DIRECTIONS = 16


class ScheuermannPoints(eqx.Module):
    """The per-point inputs only the Scheuermann model needs (JAX arrays in `Geometry`,
    NumPy arrays from `scheuermann_inputs`): unit strand normal N ⟂ T (0 where T = 0),
    the shift texture's value σ and the noise mask m."""

    normal: Float[ArrayLike, "P 3"]
    shift: Float[ArrayLike, " P"]
    mask: Float[ArrayLike, " P"]


def _table(name: str, value, width: int | None) -> tuple:
    """A 1-D texture: a non-empty list of numbers in [0, 1] (width None) or of RGB ≥ 0."""
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        arr = np.full((0,), np.nan)
    shape_ok = arr.ndim == 1 if width is None else (arr.ndim == 2 and arr.shape[1] == width)
    if (
        not shape_ok
        or len(arr) < 1
        or not np.all(np.isfinite(arr))
        or np.any(arr < 0)
        or (width is None and np.any(arr > 1))
    ):
        what = "numbers in [0, 1]" if width is None else "RGB triples of numbers ≥ 0"
        raise SceneError(f"shading.{name} must be a non-empty list of {what}, got {value!r}")
    return tuple(tuple(float(x) for x in row) for row in arr) if width else tuple(float(x) for x in arr)


@dataclasses.dataclass(frozen=True)
class ScheuermannMaps:
    """How the Scheuermann model's per-point inputs are made (docs/model.md §17).

    - `normal_center`: the strand normal points away from this point (default None: the
      centre of the roots' bounding box).
    - `texture_seed`: the seed of the shift texture and the noise mask.
    - `shift_noise`: the shift texture's amplitude a: σ = a·(U − ½) per strand, U ~ U[0, 1)
      (a = 1 is scheuermann-2004's tex − 0.5 for a texture spanning [0, 1]).
    - `mask_noise`: the noise mask's depth b: m = 1 − b·U per point (0: no mask).
    - `base_texture`, `alpha_texture`, `occlusion`: 1-D textures over the position
      u ∈ [0, 1] along the strand (root 0, tip 1), equally spaced samples, linearly
      interpolated: base colour (RGB ≥ 0), opacity factor and ambient occlusion (each in
      [0, 1]).
    - `hair_occlusion`: κ_ao > 0 multiplies the ambient occlusion by the hair's own, the
      mean of exp(−κ_ao·Ω) over directions spread on the sphere (`hair_occlusion`);
      0: none (no work).
    """

    normal_center: Vec3Like | None = None  # stored as a tuple of 3 floats
    texture_seed: int = 0
    shift_noise: float = 1.0
    mask_noise: float = 1.0
    # Each a list or tuple (a scene file gives lists), stored as a tuple once checked.
    base_texture: Sequence[Any] = ((1.0, 1.0, 1.0),)
    alpha_texture: Sequence[Any] = (1.0,)
    occlusion: Sequence[Any] = (1.0,)
    hair_occlusion: float = 0.0

    def __post_init__(self):
        if self.normal_center is not None:
            c = np.asarray(self.normal_center, dtype=np.float64)
            if c.shape != (3,) or not np.all(np.isfinite(c)):
                raise SceneError(
                    f"shading.normal_center must be 3 finite numbers, got {self.normal_center!r}"
                )
            object.__setattr__(self, "normal_center", tuple(float(x) for x in c))
        seed = self.texture_seed
        if isinstance(seed, bool) or int(seed) != seed or seed < 0:
            raise SceneError(f"shading.texture_seed must be an integer >= 0, got {seed!r}")
        object.__setattr__(self, "texture_seed", int(seed))
        if not (np.isfinite(self.shift_noise) and self.shift_noise >= 0):
            raise SceneError(f"shading.shift_noise must be >= 0, got {self.shift_noise!r}")
        if not (0 <= self.mask_noise <= 1):
            raise SceneError(f"shading.mask_noise must be in [0, 1], got {self.mask_noise!r}")
        object.__setattr__(self, "shift_noise", float(self.shift_noise))
        object.__setattr__(self, "mask_noise", float(self.mask_noise))
        object.__setattr__(self, "base_texture", _table("base_texture", self.base_texture, 3))
        object.__setattr__(self, "alpha_texture", _table("alpha_texture", self.alpha_texture, None))
        object.__setattr__(self, "occlusion", _table("occlusion", self.occlusion, None))
        if not (np.isfinite(self.hair_occlusion) and self.hair_occlusion >= 0):
            raise SceneError(f"shading.hair_occlusion must be >= 0, got {self.hair_occlusion!r}")
        object.__setattr__(self, "hair_occlusion", float(self.hair_occlusion))


def strand_position(points: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """u ∈ [0, 1] per point: arc length from the root over the strand's length (`[P]`);
    0 on strands of length 0."""
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    starts = offsets[:-1]
    seg[offsets[1:-1] - 1] = 0.0  # the gap between one strand's tip and the next root
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    strand = np.repeat(np.arange(len(starts)), np.diff(offsets))
    arc = cum - cum[starts][strand]
    total = (cum[offsets[1:] - 1] - cum[starts])[strand]
    # Fires on strands of length 0 (one point, or all points equal): u = 0.
    return np.where(total > 0, arc / np.where(total > 0, total, 1.0), 0.0)


def strand_normals(points: np.ndarray, tangent: np.ndarray, center) -> np.ndarray:
    """Unit N ⟂ T pointing away from `center`: r − (r·T)T normalised, r = p − centre
    (`[P, 3]`); 0 where T = 0."""
    r = points - np.asarray(center, dtype=np.float64)
    n = r - np.sum(r * tangent, axis=1, keepdims=True) * tangent
    norm = np.linalg.norm(n, axis=1)
    # Fallback fires where the strand runs straight at or away from the centre (r ∥ T, e.g. a
    # fur ball's roots, or r = 0): no "away" there, so any perpendicular will do; we take the
    # world axis least aligned with T, made perpendicular.
    degenerate = norm <= 1e-9 * np.maximum(np.linalg.norm(r, axis=1), 1e-300)
    axis = np.eye(3)[np.argmin(np.abs(tangent), axis=1)]
    fallback = axis - np.sum(axis * tangent, axis=1, keepdims=True) * tangent
    n = np.where(degenerate[:, None], fallback, n)
    norm = np.linalg.norm(n, axis=1, keepdims=True)
    has_tangent = np.sum(tangent * tangent, axis=1, keepdims=True) > 0.5
    # Fires at points without tangent (norm 0 there too): N = 0, ambient only.
    return np.where(has_tangent, n / np.where(has_tangent, norm, 1.0), 0.0)


def _sample(table: Sequence[Any], u: np.ndarray) -> np.ndarray:
    values = np.asarray(table, dtype=np.float64)
    grid = np.linspace(0.0, 1.0, len(values))
    if values.ndim == 1:
        return np.interp(u, grid, values)
    return np.stack([np.interp(u, grid, values[:, c]) for c in range(values.shape[1])], axis=1)


def scheuermann_inputs(strands, tangent: np.ndarray, maps: ScheuermannMaps):
    """The per-point inputs of the Scheuermann model, in NumPy.

    **Returns:** `(points, colour_factor [P, 3], segment_alpha [E] or None)`: the
    `ScheuermannPoints` (N, σ, m), the factor base(u)·AO that multiplies the per-point
    colour, and the alpha texture per segment (at the mean u of its ends; None when the
    texture is 1 everywhere, so the opacity is left untouched).
    """
    points, offsets = strands.points, strands.offsets
    centre = maps.normal_center if maps.normal_center is not None else hair_centre(points, offsets)
    normal = strand_normals(points, tangent, centre)
    rng = np.random.default_rng(maps.texture_seed)
    shift = maps.shift_noise * (rng.random(strands.num_strands) - 0.5)
    mask = 1.0 - maps.mask_noise * rng.random(strands.num_points)
    u = strand_position(points, offsets)
    seg_alpha = segment_alpha(strands, maps, u)
    occlusion = _sample(maps.occlusion, u)
    if maps.hair_occlusion > 0:
        occlusion = occlusion * hair_occlusion(strands, maps.hair_occlusion, seg_alpha)
    factor = _sample(maps.base_texture, u) * occlusion[:, None]
    pts = ScheuermannPoints(normal=normal, shift=shift[strands.strand_of_point], mask=mask)
    return pts, factor, seg_alpha


def segment_alpha(strands, maps: ScheuermannMaps, u: np.ndarray | None = None) -> np.ndarray | None:
    """The alpha texture per segment, at the mean u of its ends (`[E]`); None when it is 1
    everywhere (the opacity is then left untouched). `u`: `strand_position`, if known."""
    if all(a == 1.0 for a in maps.alpha_texture):
        return None
    u = strand_position(strands.points, strands.offsets) if u is None else u
    seg = strands.segments()
    return _sample(maps.alpha_texture, 0.5 * (u[seg[:, 0]] + u[seg[:, 1]]))


def sphere_directions(n: int) -> np.ndarray:
    """n unit vectors spread evenly over the sphere (the Fibonacci lattice, `[n, 3]`)."""
    k = np.arange(n) + 0.5
    y = 1.0 - 2.0 * k / n
    r = np.sqrt(1.0 - y * y)
    phi = np.pi * (3.0 - np.sqrt(5.0)) * k
    return np.stack([r * np.cos(phi), y, r * np.sin(phi)], axis=1)


def hair_occlusion(strands, density: float, seg_alpha: np.ndarray | None = None) -> np.ndarray:
    """Ambient occlusion by the hair itself, per point (`[P]`, in (0, 1]): the mean over
    HAIR_OCCLUSION_DIRECTIONS directions d (`sphere_directions`) of exp(−density·Ω_d), Ω_d
    the summed alpha in front of the point seen from d: §7's `exact` Ω for a directional
    light from d on a HAIR_OCCLUSION_RESOLUTION² raster, with the strands' opacity (and
    alpha texture, `seg_alpha`). NumPy, precomputed: not differentiated in the opacity."""
    segments = strands.segments()
    seg_strand = strands.strand_of_point[segments[:, 0]]
    total = np.zeros(strands.num_points)
    exact = ExactShadows(resolution=HAIR_OCCLUSION_RESOLUTION)
    for d in sphere_directions(HAIR_OCCLUSION_DIRECTIONS):
        inputs = ShadowInputs(
            strands.points,
            segments,
            seg_strand,
            strands.width,
            Light(direction=tuple(-d)),
            segment_alpha=seg_alpha,
            width_units=strands.width_units,
        )
        setup = exact.setup(inputs)
        omega = exact.omega_numpy(setup, strands.alpha)
        total += np.exp(-density * omega)
    return total / HAIR_OCCLUSION_DIRECTIONS
