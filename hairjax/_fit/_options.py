"""What `fit` is given besides the scenes, the start and the solver, in three records, as
optimistix groups a solve's options (docs/fitting.md): the targets with their masks,
weights and held-out views (`FitTargets`), what is fitted (`FitVariables`), and when the
solve stops (`FitStop`). Each checks its values when it is built, before any work."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import numpy as np

from .._shading import LightParams
from ._convergence import MAX_RESTARTS, STALL_STEPS
from ._lit import LIGHT_NAMES
from ._opacity_fit import ALPHA
from ._result import FitError

__all__ = ["FitTargets", "FitVariables", "FitStop", "image_list"]


def image_list(images) -> list:
    """One `[H, W, C]` image, or a sequence of them, as a list."""
    return [images] if np.ndim(images) == 3 else list(images)


@dataclasses.dataclass(frozen=True, eq=False)
class FitTargets:
    """The images a fit matches, with their masks and weights, and the views it holds out.

    **Fields:**
    - `images`: an `[H, W, 3|4]` linear image, or a sequence of them, one per scene of the
      fit (alpha is ignored).
    - `masks`, `weights`: None, or one entry per image: an `[H, W]` boolean pixel mask or
      `[H, W]` weights, or None for an image without (docs/fitting.md, "Target images and
      masks").
    - `holdout`: `(scene or scenes, image or images)` the fit does not see, paired like the
      fit's scenes and `images`; the result's `holdout_rmse` is the fitted parameters' RMSE
      on them (docs/fitting.md, "Held-out views and lights").

    FitError at construction for a mask or weight count other than the images' or a
    `holdout` that is not a pair.
    """

    images: Any
    masks: Sequence | None = None
    weights: Sequence | None = None
    holdout: tuple | None = None

    def __post_init__(self):
        count = len(image_list(self.images))
        for what, given in (("masks", self.masks), ("weights", self.weights)):
            if given is not None and len(given) != count:
                raise FitError(
                    f"{len(given)} {what} for {count} target images: one per image (None for none)"
                )
        if self.holdout is not None and (not isinstance(self.holdout, tuple) or len(self.holdout) != 2):
            raise FitError("holdout must be a (scene or scenes, target or targets) pair")

    def per_image(self) -> list[tuple]:
        """(image, mask, weight) for each image, None where it has no mask or weight."""
        images = image_list(self.images)
        masks = [None] * len(images) if self.masks is None else list(self.masks)
        weights = [None] * len(images) if self.weights is None else list(self.weights)
        return list(zip(images, masks, weights))


@dataclasses.dataclass(frozen=True, eq=False)
class FitVariables:
    """What a fit varies, and how.

    **Fields:**
    - `names`: the parameters to fit, among the shading model's `fittable` (None: all of
      them): kd, ks, shininess, kappa for Kajiya-Kay; kd, primary_color, primary_exponent,
      primary_shift, secondary_color, secondary_exponent, secondary_shift, kappa for
      Scheuermann (docs/model.md §17); and, for any model and only where named: ambient (a
      gain, solved for like Kd), a `searched` parameter the model leaves out of `fittable`,
      the light's light_direction (a directional light's) and light_color (docs/fitting.md,
      "Fitting the light"), and alpha, one opacity for every strand, starting from the
      first scene's mean (docs/fitting.md, "Fitting the strands' opacity"). The rest stay
      at the fit's `init` and at `light`.
    - `scalar`: among the fitted RGB parameters (the gains: kd, ks; Scheuermann's colours;
      an RGB searched parameter; light_color), those fitted as one grey value instead of
      RGB. None: the fitted gains among the model's `grey` (none for Kajiya-Kay and
      Scheuermann); a sequence, `()` included, says it in full (docs/fitting.md, "What a
      model declares").
    - `light`: the light's starting (and held) `LightParams`; None: the scenes' light.
      Given, or with a light name in `names`, the image is the shading stage's with this
      light (Ω and V stay the scenes' light's).
    - `separable`: solve the fitted gains by non-negative linear least squares at every
      step (variable projection; the image is linear in them) so that the solver iterates
      on the model's searched parameters (shininess, κ, …) only; a fit of gains alone is
      then one solve. False: the solver iterates on every fitted parameter
      (docs/fitting.md, "Variable projection").

    FitError at construction for names given as one string, or alpha with the light.
    """

    names: Sequence[str] | None = None
    scalar: Sequence[str] | None = None
    light: LightParams | None = None
    separable: bool = True

    def __post_init__(self):
        for what, given in (("names", self.names), ("scalar", self.scalar)):
            if isinstance(given, str):
                raise FitError(f"FitVariables.{what} is a sequence of names, got the string {given!r}")
        if self.opacity and self.lit:
            raise FitError(f"{ALPHA} is not fitted together with the light (light_direction, light_color)")

    @property
    def lit(self) -> bool:
        """The image is the shading stage's at a light the fit holds or fits."""
        return self.light is not None or (
            self.names is not None and any(n in LIGHT_NAMES for n in self.names)
        )

    @property
    def opacity(self) -> bool:
        """The strands' opacity is fitted."""
        return self.names is not None and ALPHA in self.names


@dataclasses.dataclass(frozen=True)
class FitStop:
    """When a fit stops (docs/fitting.md, "When a fit has converged"); the tolerances are
    the solver's `rtol` and `atol`.

    **Fields:**
    - `max_steps`: the most solver steps; the fit stops there, unconverged.
    - `max_restarts`: how often the solver is started afresh from its point where its own
      tolerance test passed but Gauss-Newton still predicts a decrease beyond the
      tolerances, or a parameter without effect leaves a lower plateau to try.
    - `stall_steps`: after this many steps without a lower loss the convergence test is
      applied whatever the solver's own test says (a trust region at the float32 floor
      rejects every step).
    - `throw`: raise `FitNotConverged` (with the result) where the fit stops without
      converging, instead of returning the result with its `termination`.
    """

    max_steps: int = 100
    max_restarts: int = MAX_RESTARTS
    stall_steps: int = STALL_STEPS
    throw: bool = False

    def __post_init__(self):
        for name, least in (("max_steps", 0), ("max_restarts", 0), ("stall_steps", 1)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < least:
                raise FitError(f"FitStop.{name} must be an integer >= {least}, got {value!r}")
