"""Held-out views and lights: how well fitted parameters hold on images the fit did not
see (docs/fitting.md, "Held-out views and lights").

The held-out RMSE is the training RMSE's definition (`FitResult.rmse`) on other targets:
√(Σ w·(image − target)² / (3·N)) over the N pixels of positive weight, pooled over every
held-out target. The image is the renderer's (`render`, or the shading stage at a fitted
light), so it includes the fragments that the fit drops behind transmittance below
`FIT_TRANSMITTANCE_CUTOFF` (their effect is below 1e-5 of the brightest colour).
"""

from __future__ import annotations

from collections.abc import Sequence

import jax.numpy as jnp
import numpy as np

from .._geometry_stage._stage import geometry_stage
from .._render import render
from .._scene._scene import Scene
from .._shading import shading_stage
from ._opacity_fit import strand_alpha
from ._problem import target_arrays
from ._result import FitError, FitResult

__all__ = ["HeldOut", "fitted_image", "held_out", "held_out_rmse"]

HeldOut = list[tuple[Scene, np.ndarray, np.ndarray]]  # (scene, target [HW, 3], √weight [HW, 1])


def held_out(scene: Scene | Sequence[Scene], targets, masks=None, weights=None) -> HeldOut:
    """The held-out targets checked (size, NaN pixels, weights) and paired with their
    scenes like `fit`'s: one scene serves every target. FitError before any work."""
    scenes = [scene] if isinstance(scene, Scene) else list(scene)
    target_list = [targets] if np.ndim(targets) == 3 else list(targets)
    if len(scenes) == 1 and len(target_list) > 1:
        scenes = scenes * len(target_list)
    if len(scenes) != len(target_list) or not scenes:
        raise FitError(f"holdout: {len(scenes)} scenes for {len(target_list)} targets")
    mask_list = [None] * len(scenes) if masks is None else list(masks)
    weight_list = [None] * len(scenes) if weights is None else list(weights)
    return [
        (s, *target_arrays(s, t, m, w)) for s, t, m, w in zip(scenes, target_list, mask_list, weight_list)
    ]


def check_light(heldout: HeldOut, training: Sequence[Scene], lit: bool) -> None:
    """A fit of the light renders its held-out targets at the fitted light, so they must
    share the training scenes' light (Ω is computed at it): FitError otherwise."""
    if lit and any(s.light != training[0].light for s, _, _ in heldout):
        raise FitError(
            "holdout: a fit of the light renders its held-out views at the fitted light, so their "
            "scenes need the training scenes' light; hold out a light with the light held"
        )


def fitted_image(scene: Scene, result: FitResult):
    """`scene` rendered `[H, W, 4]` with `result`'s parameters, and its fitted light (Ω and
    V stay the scene's light's, as in the fit) or strands' opacity where it fitted them."""
    if result.light is not None:
        return shading_stage(geometry_stage(scene), result.params, result.light)
    if result.alpha is not None:
        return render(scene, result.params, strand_alpha(scene, result.alpha))
    return render(scene, result.params)


def held_out_rmse(result: FitResult, heldout: HeldOut) -> float:
    """The RMSE of `result`'s parameters (and fitted light or opacity) on the `held_out`
    targets."""
    total, count = 0.0, 0.0
    for scene, target, sqrt_weight in heldout:
        image = fitted_image(scene, result)
        rgb = np.asarray(jnp.asarray(image)[..., :3], np.float64).reshape(-1, 3)
        total += float(np.sum((sqrt_weight * (rgb - target)) ** 2))
        count += 3.0 * np.count_nonzero(sqrt_weight)
    return float(np.sqrt(total / max(count, 1.0)))  # max: fires when every weight is 0
