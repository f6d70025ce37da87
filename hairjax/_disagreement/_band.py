"""`renderer_band`: the pixels where the two renderers may differ, the camera and light
sides summed (docs/model.md §11)."""

from __future__ import annotations

import numpy as np

from .._cache import cached
from .._geometry_stage._stage import geometry_stage
from .._scene._scene import Scene
from ._camera import camera_risk
from ._light import omega_uncertainty, transmittance_uncertainty
from ._occluder import occluder_light_uncertainty
from ._tolerances import PIXEL_TOL

__all__ = ["renderer_band"]


def _risk(scene: Scene, shadows: bool) -> tuple[np.ndarray, np.ndarray]:
    """Per pixel (row-major): the summed weight α·T of fragments near a segment end, plus
    with `shadows` each other fragment's weight times how much its τ may differ (the larger
    of its ends' `transmittance_uncertainty`); and the pixels at the occluder's silhouette
    or depth (in the band whatever the colour). Cached per scene object (`_cache`)."""
    cache = cached(scene, "disagreement band", dict)
    if "camera" not in cache:
        cache.update(camera_risk(scene))
    if shadows and "either" not in cache:
        cache["either"] = cache["camera"]
        cache["always_either"] = cache["always"]
        if scene.shadows.casts:
            # A fragment's colour mixes its segment's end colours, each moving by ≤ Δτ × its
            # fully lit colour: by ≤ max(Δτ₀, Δτ₁) × colour_bound.
            omega = np.asarray(geometry_stage(scene).omega, np.float64)
            dtau = transmittance_uncertainty(omega, omega_uncertainty(scene))
            if scene.occluder is not None:
                # §13: where GL's V or the occluder's Ω may differ, anything may.
                unsure_points, unsure_pixels = occluder_light_uncertainty(scene)
                dtau = np.where(unsure_points, 1.0, dtau)
                cache["always_either"] = cache["always"] | unsure_pixels
            i0, i1 = cache["ends"]
            risk = np.where(cache["near_end"], 0.0, np.maximum(dtau[i0], dtau[i1]))
            cache["either"] = cache["camera"] + np.bincount(
                cache["pixel"], cache["weights"] * risk, minlength=cache["camera"].size
            )
    if shadows:
        return cache["either"], cache["always_either"]
    return cache["camera"], cache["always"]


def renderer_band(scene: Scene, colour_bound: float = 1.0) -> np.ndarray:
    """The pixels (`bool[H, W]`) where the JAX and GL renderers may differ by more than
    PIXEL_TOL (1e-4) because a discontinuity of the model lies within float32 rounding
    (docs/model.md §11), from the geometry alone: no render, no shading parameters.

    A camera fragment of compositing weight w = α·T (§6) can move its pixel by
    - w × `colour_bound` when the pixel centre lies within rounding of its segment's end
      (`end_band`): GL may draw it or not, and it replaces w of what lies behind it by its
      own colour;
    - otherwise w × Δτ × `colour_bound`, Δτ the larger `transmittance_uncertainty` of its
      segment's two end points, whose colours it mixes: GL's Ω at a point may differ by up
      to `omega_uncertainty`, τ = exp(−κΩ) then by up to Δτ whatever κ is, and the point's
      colour ambient·c + τ·light·(Kd·sin(T, L)·c + specular) by Δτ times its lit part.
    A pixel is in the band when these sum to more than PIXEL_TOL. Pixels at the occluder's
    silhouette (point-sampled, §9) or with hair at the sphere's own depth are in it
    whatever the colours. With shadows "none" only the first kind remains.

    `colour_bound`: a bound on the colours and on every point's fully lit colour; the
    image's brightest value is the practical stand-in (tests/gl/test_renderer.py and
    experiments/01_fit_recovery.py use it), 1 for images in [0, 1]. The sum is first order:
    weights as drawn, ignoring that a toggled fragment also changes T behind it. Because
    Δτ holds for every κ, a point whose Ω may differ taints every pixel of its two
    segments where they weigh enough, so the band holds more than MAX_BAND where shadows
    differ (2.7 % of the default scene at 224², docs/fitting.md); its camera part alone
    stays within MAX_BAND (tests/gl/test_renderer.py).

    The geometry, JAX's Ω (from `geometry_stage`, which needs no shading parameters)
    included, is cached per scene object: calling this for each target of a scene costs
    a comparison each.
    """
    either, always = _risk(scene, shadows=True)
    cam = scene.camera
    return ((either * colour_bound > PIXEL_TOL) | always).reshape(cam.height, cam.width)
