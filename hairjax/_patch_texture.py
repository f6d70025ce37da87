"""The hair patches' alpha texture (docs/model.md §18, scheuermann-2004 slide 6): strands
side by side across a patch, each with an opaque core (or a semi-transparent peak) and its
own length, drawn from an integer hash that hairjax/gl/shaders/patch.frag computes alike.
NumPy float64."""

from __future__ import annotations

import numpy as np

from ._constants import PATCH_OPAQUE_STRANDS

__all__ = ["patch_alpha", "patch_texture", "strand_hash"]


def patch_alpha(u: np.ndarray, core: float) -> np.ndarray:
    """One strand's profile p(t) = clamp((½ − |t − ½|) / (½ − c/2), 0, 1); 1 everywhere for
    c = 1. (The whole texture for n = 1 strand across, m = 1 and λ = 0.)"""
    half = 0.5 - 0.5 * core
    edge = 0.5 - np.abs(np.asarray(u, np.float64) - 0.5)
    # Fires for c = 1 only (no fading band): the whole patch is opaque.
    return np.clip(edge / half, 0.0, 1.0) if half > 0 else np.ones_like(edge)


def _pcg(x: np.ndarray) -> np.ndarray:
    """Jarzynski & Olano's pcg_hash ("Hash Functions for GPU Rendering", JCGT 2020) of
    uint32 `x`, arithmetic mod 2³² as GLSL's uint (patch.frag has the same lines)."""
    state = x * np.uint32(747796405) + np.uint32(2891336453)
    word = ((state >> ((state >> np.uint32(28)) + np.uint32(4))) ^ state) * np.uint32(277803737)
    return (word >> np.uint32(22)) ^ word


def strand_hash(patch: np.ndarray, strand: np.ndarray) -> np.ndarray:
    """h = pcg(k + pcg(patch)) mod 2³² for strand k of a patch (`uint32`)."""
    with np.errstate(over="ignore"):  # uint32 wrap-around is the hash's arithmetic
        patch = np.asarray(patch).astype(np.uint32)
        return _pcg(np.asarray(strand).astype(np.uint32) + _pcg(patch))


def patch_texture(
    u: np.ndarray,
    v: np.ndarray,
    patch: np.ndarray,
    core: float,
    strands: int = 1,
    strand_alpha: float = 1.0,
    tips: float = 0.0,
) -> np.ndarray:
    """The alpha texture of docs/model.md §18 at (u, v) of patch `patch`: n = `strands`
    side by side across u, strand k = min(⌊nu⌋, n − 1) at t = nu − k with a = α_k·p(t),
    and a = 0 beyond its length (v > 1 − λ g_k, only for λ = `tips` > 0). From its hash h
    (`strand_hash`): q = ⌊h/2²⁴⌋/256; α_k = 1 where q ≥ 1 − PATCH_OPAQUE_STRANDS, else
    m + (1 − m)·q/(1 − PATCH_OPAQUE_STRANDS), m = `strand_alpha`; g_k = (h mod 2¹⁶)/2¹⁶.
    Every quantity from h is a multiple of 2⁻¹⁶, exact in float32: GL decides alike."""
    u = np.asarray(u, np.float64)
    s = strands * u
    # The clip fires for u outside [0, 1] (pixels a snapped edge covers beyond the patch,
    # u by up to 1/256 px's worth): p(t) is 0 there whichever strand it names.
    k = np.clip(np.floor(s), 0, strands - 1)
    p = patch_alpha(s - k, core)
    h = strand_hash(patch, k)
    q = (h >> np.uint32(24)).astype(np.float64) / 256.0
    rest = 1.0 - PATCH_OPAQUE_STRANDS
    peak = np.where(q >= rest, 1.0, strand_alpha + (1.0 - strand_alpha) * (q / rest))
    a = peak * p
    if tips > 0:  # λ = 0: every strand runs to the tip (v ≤ 1 up to rounding)
        g = (h & np.uint32(0xFFFF)).astype(np.float64) / 65536.0
        a = np.where(np.asarray(v, np.float64) > 1.0 - tips * g, 0.0, a)
    return a
