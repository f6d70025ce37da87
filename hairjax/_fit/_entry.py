"""`hairjax.fit`: shading parameters fitted to target images with optimistix (docs/fitting.md).

The entry checks the input, sets up each target through the scenes' shading model (its
`FitModel`, `_shading_fit.fit_model`), steps the solver (`_convergence.py`) on
the residuals of `_problem.py` (the gains solved for by `_varpro.py` where the model's
image is linear in them) and builds the `FitResult`, standard errors included
(`_uncertainty.py`). Nothing here depends on which model is fitted.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Sequence

import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx

from .._scene._scene import Scene
from .._shading import AbstractShadingModel, LightParams
from ._batch import batched, batched_model
from ._convergence import half_square, plateau_exit, solve
from ._holdout import check_light, held_out, held_out_rmse
from ._light_fit import lit_fit_model, start_light
from ._lit import LIGHT_NAMES, LitParams
from ._model import FitModel
from ._opacity_fit import ALPHA, OpacityParams, opacity_fit_model, start_alpha
from ._problem import (
    Problem,
    check_names,
    jit_point,
    loss_fn,
    params_loss,
    residual_fn,
    residuals,
    target_arrays,
)
from ._result import FitError, FitResult
from ._shading_fit import fit_model, rgb_searched
from ._solvers import default_tolerances, is_least_squares
from ._space import to_flat
from ._uncertainty import standard_errors

__all__ = ["fit"]


def fit(
    scene: Scene | Sequence[Scene],
    targets,
    fit: Sequence[str] | None = None,
    init=None,
    solver=None,
    *,
    masks=None,
    weights=None,
    scalar: Sequence[str] | None = None,
    max_steps: int = 100,
    light: LightParams | None = None,
    separable: bool = True,
    progress: Callable[[int, float, float], None] | None = None,
    holdout=None,
) -> FitResult:
    """Least-squares fit of shading parameters to one or more target images.

    **Arguments:**
    - `scene`: a Scene, or one per target (the same hair under several views or lights).
    - `targets`: an `[H, W, 3|4]` linear image, or a list of them (alpha is ignored).
    - `fit`: the parameters to fit, among the shading model's `fittable` (default: all of
      them): kd, ks, shininess, kappa for Kajiya-Kay; kd, primary_color, primary_exponent,
      primary_shift, secondary_color, secondary_exponent, secondary_shift, kappa for
      Scheuermann (docs/model.md §17); and, for any model and only where named: ambient
      (a gain, solved for like Kd), a `searched` parameter the model leaves out of
      `fittable`, the light's light_direction (a directional light's)
      and light_color (docs/fitting.md, "Fitting the light"), and alpha, one opacity for
      every strand, starting from the first scene's mean (docs/fitting.md, "Fitting the
      strands' opacity"); the rest stay at `init` and `light`.
    - `init`: starting (and fixed) parameters, the model's parameter type; default the
      first scene's.
    - `solver`: an optimistix least-squares solver or minimiser (a minimiser is given
      ½‖r‖²), whose `rtol` and `atol` are the fit's tolerances: e.g.
      `optimistix.LevenbergMarquardt(rtol=1e-5, atol=1e-7)`, `hairjax.GaussNewton(...)`
      (damped), `hairjax.BFGS(...)` (a scaled first step), or `hairjax.fit_solvers()[name]`,
      the four the CLI's `--solver` names, with the working precision's tolerances. Default
      (None): Levenberg-Marquardt with those tolerances (1e-8 and 1e-10 in float64, 1e-5
      and 1e-7 in float32: tighter than float32 resolves only adds steps that change
      nothing).
    - `light`: the light's starting (and held) `LightParams`; default the scenes' light.
      Given, or with a light name in `fit`, the image is the shading stage's with this
      light (Ω and V stay the scenes' light's).
    - `masks`, `weights`: optional per-target `[H, W]` pixel masks and weights.
    - `scalar`: among the fitted RGB parameters (the gains: kd, ks; Scheuermann's colours;
      an RGB searched parameter; light_color), those fitted as one grey value instead of
      RGB. None (the default): the fitted gains among the model's `grey` (none for
      Kajiya-Kay and Scheuermann); a sequence, `()` included, says it in full
      (docs/fitting.md, "What a model declares").
    - `separable`: solve the fitted gains by non-negative linear least squares at every
      step (variable projection; the image is linear in them) so that the solver iterates
      on the model's searched parameters (shininess, κ, …) only; a fit of gains alone is
      then one solve. False: the solver iterates on every fitted parameter (docs/fitting.md).
    - `progress(step, loss, elapsed_s)`: called after every step.
    - `holdout`: `(scene or scenes, target or targets)` the fit does not see, paired like
      `scene` and `targets`; the result's `holdout_rmse` is the fitted parameters' RMSE on
      them (docs/fitting.md, "Held-out views and lights"). Checked before the fit starts.

    **Returns:** a `FitResult`.
    """
    scenes = [scene] if isinstance(scene, Scene) else list(scene)
    target_list = [targets] if np.ndim(targets) == 3 else list(targets)
    if len(scenes) == 1 and len(target_list) > 1:
        scenes = scenes * len(target_list)
    if len(scenes) != len(target_list):
        raise FitError(f"{len(scenes)} scenes for {len(target_list)} targets")
    mask_list = [None] * len(scenes) if masks is None else list(masks)
    weight_list = [None] * len(scenes) if weights is None else list(weights)
    if any(s.patches is not None for s in scenes):  # docs/model.md §18: not wired into the fit
        raise FitError("fit does not support hair-patch scenes (hair.geometry = 'patches')")
    lit = light is not None or (fit is not None and any(n in LIGHT_NAMES for n in fit))
    opacity = fit is not None and ALPHA in fit
    if opacity and lit:
        raise FitError(f"{ALPHA} is not fitted together with the light (light_direction, light_color)")
    init = scenes[0].params if init is None else init
    model = _model_of(scenes, lit, opacity, init)
    names = check_names(model.defaults if fit is None else fit, () if scalar is None else scalar, model)
    scalar = tuple(n for n in model.grey if n in names) if scalar is None else tuple(scalar)
    if solver is None:
        rtol, atol = default_tolerances()
        solver = optx.LevenbergMarquardt(rtol=rtol, atol=atol)
    least_squares = is_least_squares(solver)
    rtol, atol = float(solver.rtol), float(solver.atol)
    arrays = [target_arrays(s, t, m, w) for s, t, m, w in zip(scenes, target_list, mask_list, weight_list)]
    if not isinstance(init, model.params_type):
        raise FitError(
            f"a {model.label} scene is fitted from {model.params_type.__name__}, got {type(init).__name__}"
        )
    heldout = None
    if holdout is not None:
        if not isinstance(holdout, tuple) or len(holdout) != 2:
            raise FitError("holdout must be a (scene or scenes, target or targets) pair")
        heldout = held_out(*holdout)
        check_light(heldout, scenes, lit)
        if any(type(s.shading) is not type(scenes[0].shading) for s, _, _ in heldout):
            raise FitError("holdout: the held-out scenes need the training scenes' shading model")
    initial, initial_light = init, None
    if lit:  # the light joins the model's parameters (docs/fitting.md, "Fitting the light")
        initial_light = start_light(scenes, names, light)
        init = LitParams(init, initial_light)
    initial_alpha = start_alpha(scenes) if opacity else None
    if opacity:  # the strands' opacity joins them (docs/fitting.md, "Fitting the strands' opacity")
        init = OpacityParams(init, jnp.asarray(initial_alpha, dtype=jnp.result_type(float)))

    start = time.perf_counter()
    data = [model.prepare(s, init, names, t, sw) for s, (t, sw) in zip(scenes, arrays)]
    stacked = batched(data)  # several targets: one batch under vmap where they stack
    if stacked is not data:
        data, model = stacked, batched_model(model)
    jax.block_until_ready(data)
    geometry_s = time.perf_counter() - start

    # The solver iterates on z over `solved`; the fitted gains in `linear` are solved for.
    linear = tuple(n for n in model.linear if separable and n in names)
    solved = tuple(n for n in names if n not in linear)
    problem = Problem(data, init, model, solved, linear, scalar)
    z = to_flat(init, solved, scalar, model.transforms)
    fn = residual_fn if least_squares else loss_fn
    # loss[0] is the loss at `init` itself, its gains included (not at the solved gains).
    losses = [float(params_loss(init, model, data))]

    def report(step, loss):
        if progress is not None:
            progress(step, loss, time.perf_counter() - start - geometry_s)

    if not solved:
        # Only gains are fitted: one linear least-squares solve is the whole fit.
        steps, termination, restarts, diverged = 1, "converged", 0, False
        losses.append(float(half_square(residuals, z, problem)))
        report(steps, losses[-1])
    else:
        z, steps, termination, restarts, diverged = solve(
            solver,
            fn,
            residuals,
            z,
            problem,
            losses,
            max_steps=max_steps,
            rtol=rtol,
            atol=atol,
            report=report,
            plateau=lambda z, effect, loss: plateau_exit(residuals, z, problem, effect, loss, rtol, atol),
        )
    fitted = jit_point(z, problem)[0]
    params, fitted_light = (fitted.shading, fitted.light) if lit else (fitted, None)
    params, fitted_alpha = (fitted.shading, float(fitted.alpha)) if opacity else (params, None)
    elapsed = time.perf_counter() - start - geometry_s

    std_error, undetermined = standard_errors(model, data, fitted, names, scalar)
    n_pixels = float(sum(np.count_nonzero(np.asarray(d.sqrt_weight)) for d in data)) * 3
    # At the returned point (a diverged fit's last loss is not).
    final_loss = float(half_square(residuals, z, problem)) if diverged else losses[-1]
    rmse = float(np.sqrt(2 * final_loss / max(n_pixels, 1.0)))
    result = FitResult(
        params=params,
        initial=initial,
        fitted=names,
        loss=losses,
        steps=steps,
        time_s=elapsed,
        geometry_s=geometry_s,
        termination=termination,
        std_error=std_error,
        undetermined=undetermined,
        rmse=rmse,
        restarts=restarts,
        light=fitted_light,
        initial_light=initial_light,
        alpha=fitted_alpha,
        initial_alpha=initial_alpha,
    )
    if heldout is None:
        return result
    return dataclasses.replace(result, holdout_rmse=held_out_rmse(result, heldout))


def _model_of(scenes, lit: bool, opacity: bool, init) -> FitModel:
    """The fit of the scenes' shading model (`fit_model`; with the light, `lit_fit_model`;
    with the strands' opacity, `opacity_fit_model`), its RGB searched parameters those
    that hold 3 values in `init`; FitError where the scenes' models differ."""
    classes: list[type[AbstractShadingModel]] = list(dict.fromkeys(type(s.shading) for s in scenes))
    if len(classes) > 1:
        raise FitError(
            "scenes of one fit share a shading model; got " + " and ".join(c.name for c in classes)
        )
    make = lit_fit_model if lit else opacity_fit_model if opacity else fit_model
    # A class and names: hashable, cached.
    return make(classes[0], rgb_searched(classes[0], init))
