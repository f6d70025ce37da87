"""The problem a fit solves (docs/fitting.md, "The problem"): the targets and their
weights, and the fragments a fit keeps."""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .._constants import FIT_TRANSMITTANCE_CUTOFF
from .._scene import Scene
from ._result import FitError

__all__ = ["target_arrays", "visible_fragments"]


def target_arrays(scene: Scene, target, mask, weight):
    """(target `[HW, 3]`, √weight `[HW, 1]`) of one target, its alpha dropped and its mask
    folded into the weights; FitError for a wrong size, NaN pixels or bad weights."""
    h, w = scene.camera.height, scene.camera.width
    image = np.asarray(target, dtype=np.float64)
    if image.ndim != 3 or image.shape[2] < 3:
        raise FitError(f"target for {scene.name!r} must be [H, W, 3 or 4], got {image.shape}")
    if image.shape[:2] != (h, w):
        raise FitError(f"target is {image.shape[1]}x{image.shape[0]} but scene {scene.name!r} "
                       f"renders {w}x{h}")
    if not np.all(np.isfinite(image[..., :3])):
        raise FitError(f"target for {scene.name!r} has NaN or infinite pixels")
    wt = np.ones((h, w)) if weight is None else np.broadcast_to(np.asarray(weight, float), (h, w))
    if mask is not None:
        wt = wt * (np.broadcast_to(np.asarray(mask), (h, w)) > 0)
    if not np.all(np.isfinite(wt)) or np.any(wt < 0):
        raise FitError("weights must be finite and non-negative")
    return image[..., :3].reshape(-1, 3), np.sqrt(wt).reshape(-1, 1)


def visible_fragments(geom):
    """The geometry without fragments behind transmittance < FIT_TRANSMITTANCE_CUTOFF
    (their total weight per pixel is below the cutoff: see hairjax/_constants.py)."""
    weight = np.asarray(geom.frag_weight)
    # T_k = w_k / α_k; a fragment with w = 0 (behind an opaque one, or α·T underflowing)
    # carries nothing and is dropped as well.
    alpha = np.asarray(geom.frag_alpha)
    keep = np.flatnonzero(weight >= FIT_TRANSMITTANCE_CUTOFF * alpha)
    return eqx.tree_at(lambda g: (g.frag_pixel, g.frag_i0, g.frag_t, g.frag_weight, g.frag_alpha),
                       geom, tuple(jnp.asarray(np.asarray(x)[keep]) for x in (
                           geom.frag_pixel, geom.frag_i0, geom.frag_t, geom.frag_weight,
                           geom.frag_alpha)))
