"""`hairjax.fit`: shading parameters fitted to target images with optimistix (docs/fitting.md).

The entry checks the input (`FitTargets`, `FitVariables`, `FitStop`: `_options.py`), sets
up each target through the scenes' shading model (its `FitModel`,
`_shading_fit.fit_model`), steps the solver (`_convergence.py`) on the residuals of
`_problem.py` (the gains solved for by `_varpro.py` where the model's image is linear in
them) and builds the `FitResult`, standard errors included (`_uncertainty.py`). Nothing
here depends on which model is fitted.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Sequence
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx

from .._scene._scene import Scene
from .._shading import AbstractShadingModel
from ._batch import batched, batched_model
from ._convergence import Solved, half_square, plateau_exit, solve
from ._holdout import HeldOut, check_light, held_out, held_out_rmse
from ._light_fit import lit_fit_model, start_light
from ._lit import LitParams
from ._model import FitModel
from ._opacity_fit import OpacityParams, opacity_fit_model, start_alpha
from ._options import FitStop, FitTargets, FitVariables
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
from ._result import FitError, FitNotConverged, FitResult
from ._shading_fit import fit_model, rgb_searched
from ._solvers import default_tolerances, is_least_squares
from ._space import to_flat
from ._uncertainty import standard_errors

__all__ = ["fit"]


def fit(
    scene: Scene | Sequence[Scene],
    targets: FitTargets | Any,
    solver=None,
    *,
    init=None,
    variables: FitVariables | Sequence[str] | None = None,
    stop: FitStop = FitStop(),
    progress: Callable[[int, float, float], None] | None = None,
) -> FitResult:
    """Least-squares fit of shading parameters to one or more target images.

    **Arguments:**
    - `scene`: a Scene, or one per target (the same hair under several views or lights).
    - `targets`: a `FitTargets` (the images with their masks, weights and held-out views),
      or only the images: an `[H, W, 3|4]` linear image or a list of them (alpha is
      ignored), as `FitTargets(targets)`.
    - `solver`: an optimistix least-squares solver or minimiser (a minimiser is given
      ½‖r‖²), whose `rtol` and `atol` are the fit's tolerances: e.g.
      `optimistix.LevenbergMarquardt(rtol=1e-5, atol=1e-7)`, `hairjax.GaussNewton(...)`
      (damped), `hairjax.BFGS(...)` (a scaled first step), or `hairjax.fit_solvers()[name]`,
      the four the CLI's `--solver` names, with the working precision's tolerances. Default
      (None): Levenberg-Marquardt with those tolerances (1e-8 and 1e-10 in float64, 1e-5
      and 1e-7 in float32: tighter than float32 resolves only adds steps that change
      nothing).
    - `init`: starting (and fixed) parameters, the model's parameter type; default the
      first scene's.
    - `variables`: a `FitVariables`, what is fitted (the names, those fitted grey, the
      light held or started from, variable projection), or only the names, as
      `FitVariables(variables)`; None: `FitVariables()`, the model's `fittable`.
    - `stop`: a `FitStop`, when the fit stops (`max_steps`, 100 by default; restarts;
      `throw`).
    - `progress(step, loss, elapsed_s)`: called after every step.

    **Returns:** a `FitResult`.

    **Raises:** `FitError` for bad input, before any work (the held-out targets included);
    `FitNotConverged` where the fit stopped without converging and `stop.throw` is set.
    """
    targets = targets if isinstance(targets, FitTargets) else FitTargets(targets)
    variables = variables if isinstance(variables, FitVariables) else FitVariables(variables)
    if not isinstance(stop, FitStop):
        raise FitError(f"stop must be a FitStop (e.g. hairjax.FitStop(max_steps=200)), got {stop!r}")
    if solver is None:
        rtol, atol = default_tolerances()
        solver = optx.LevenbergMarquardt(rtol=rtol, atol=atol)
    least_squares = is_least_squares(solver)
    start = _start(scene, targets, variables, init)

    clock = time.perf_counter()
    data, model = _prepared(start)
    jax.block_until_ready(data)
    geometry_s = time.perf_counter() - clock

    def report(step, loss):
        if progress is not None:
            progress(step, loss, time.perf_counter() - clock - geometry_s)

    problem = _problem(start, data, model, variables.separable)
    losses: list = []
    solved = _solve(solver, least_squares, problem, losses, stop, report)
    fitted = jit_point(solved.z, problem)[0]
    elapsed = time.perf_counter() - clock - geometry_s
    result = _result(start, problem, fitted, losses, solved, elapsed, geometry_s)
    if start.heldout is not None:
        result = dataclasses.replace(result, holdout_rmse=held_out_rmse(result, start.heldout))
    if stop.throw and result.termination != "converged":
        raise FitNotConverged(result)
    return result


class _Start(NamedTuple):
    """A fit's checked input (`_start`): the scenes and their targets' (target, √weight)
    arrays, the model's fit, the names fitted and those fitted grey, the point the solve
    starts from (the light or the strands' opacity joined to the parameters where fitted)
    and its parts, and the held-out targets."""

    scenes: list[Scene]
    arrays: list[tuple[np.ndarray, np.ndarray]]
    model: FitModel
    names: tuple[str, ...]
    scalar: tuple[str, ...]
    point: Any
    initial: Any
    initial_light: Any
    initial_alpha: float | None
    heldout: HeldOut | None


def _start(scene, targets: FitTargets, variables: FitVariables, init) -> _Start:
    """The input checked and the start set up (`_Start`); FitError before any work."""
    scenes = [scene] if isinstance(scene, Scene) else list(scene)
    per_image = targets.per_image()
    if len(scenes) == 1 and len(per_image) > 1:
        scenes = scenes * len(per_image)
    if len(scenes) != len(per_image):
        raise FitError(f"{len(scenes)} scenes for {len(per_image)} targets")
    if any(s.patches is not None for s in scenes):  # docs/model.md §18: not wired into the fit
        raise FitError("fit does not support hair-patch scenes (hair.geometry = 'patches')")
    lit, opacity = variables.lit, variables.opacity
    init = scenes[0].params if init is None else init
    model = _model_of(scenes, lit, opacity, init)
    given_scalar = () if variables.scalar is None else variables.scalar
    names = check_names(model.defaults if variables.names is None else variables.names, given_scalar, model)
    scalar = (
        tuple(n for n in model.grey if n in names) if variables.scalar is None else tuple(variables.scalar)
    )
    arrays = [target_arrays(s, t, m, w) for s, (t, m, w) in zip(scenes, per_image)]
    if not isinstance(init, model.params_type):
        raise FitError(
            f"a {model.label} scene is fitted from {model.params_type.__name__}, got {type(init).__name__}"
        )
    heldout = None if targets.holdout is None else _held_out(targets.holdout, scenes, lit)
    point, initial_light, initial_alpha = init, None, None
    if lit:  # the light joins the model's parameters (docs/fitting.md, "Fitting the light")
        initial_light = start_light(scenes, names, variables.light)
        point = LitParams(init, initial_light)
    if opacity:  # the strands' opacity joins them (docs/fitting.md, "Fitting the strands' opacity")
        initial_alpha = start_alpha(scenes)
        point = OpacityParams(init, jnp.asarray(initial_alpha, dtype=jnp.result_type(float)))
    return _Start(
        scenes=scenes,
        arrays=arrays,
        model=model,
        names=names,
        scalar=scalar,
        point=point,
        initial=init,
        initial_light=initial_light,
        initial_alpha=initial_alpha,
        heldout=heldout,
    )


def _held_out(holdout: tuple, scenes: list[Scene], lit: bool) -> HeldOut:
    """`FitTargets.holdout`'s targets checked against the training scenes (`held_out`)."""
    heldout = held_out(*holdout)
    check_light(heldout, scenes, lit)
    if any(type(s.shading) is not type(scenes[0].shading) for s, _, _ in heldout):
        raise FitError("holdout: the held-out scenes need the training scenes' shading model")
    return heldout


def _prepared(start: _Start) -> tuple[Any, FitModel]:
    """(every target's data, the model's fit) from `FitModel.prepare`: one batch under
    vmap where the targets stack (`batched`)."""
    model = start.model
    data = [
        model.prepare(s, start.point, start.names, t, sw) for s, (t, sw) in zip(start.scenes, start.arrays)
    ]
    stacked = batched(data)
    if stacked is not data:
        return stacked, batched_model(model)
    return data, model


def _problem(start: _Start, data, model: FitModel, separable: bool) -> Problem:
    """The solve's `Problem`: the solver iterates on z over `solved`; the fitted gains in
    `linear` are solved for (variable projection, where `separable`)."""
    linear = tuple(n for n in model.linear if separable and n in start.names)
    solved = tuple(n for n in start.names if n not in linear)
    return Problem(data, start.point, model, solved, linear, start.scalar)


def _solve(solver, least_squares: bool, problem: Problem, losses: list, stop: FitStop, report) -> Solved:
    """The solve from the problem's start (`_convergence.solve`), its losses appended to
    `losses`, the first the loss at the start itself, its gains included (not at the
    solved gains)."""
    model = problem.model
    z = to_flat(problem.init, problem.solved, problem.scalar, model.transforms)
    losses.append(float(params_loss(problem.init, model, problem.data)))
    if not problem.solved:
        # Only gains are fitted: one linear least-squares solve is the whole fit.
        losses.append(float(half_square(residuals, z, problem)))
        report(1, losses[-1])
        return Solved(z=z, steps=1, termination="converged", restarts=0, diverged=False)
    rtol, atol = float(solver.rtol), float(solver.atol)
    return solve(
        solver,
        residual_fn if least_squares else loss_fn,
        residuals,
        z,
        problem,
        losses,
        stop=stop,
        report=report,
        plateau=lambda z, effect, loss: plateau_exit(residuals, z, problem, effect, loss, rtol, atol),
    )


def _result(
    start: _Start, problem: Problem, fitted, losses: list, solved: Solved, time_s, geometry_s
) -> FitResult:
    """The `FitResult` at the fitted point, its standard errors and RMSE included."""
    lit, opacity = start.initial_light is not None, start.initial_alpha is not None
    params, fitted_light = (fitted.shading, fitted.light) if lit else (fitted, None)
    params, fitted_alpha = (fitted.shading, float(fitted.alpha)) if opacity else (params, None)
    data = problem.data
    std_error, undetermined = standard_errors(problem.model, data, fitted, start.names, start.scalar)
    n_pixels = float(sum(np.count_nonzero(np.asarray(d.sqrt_weight)) for d in data)) * 3
    # At the returned point (a diverged fit's last loss is not).
    final_loss = float(half_square(residuals, solved.z, problem)) if solved.diverged else losses[-1]
    return FitResult(
        params=params,
        initial=start.initial,
        fitted=start.names,
        loss=losses,
        steps=solved.steps,
        time_s=time_s,
        geometry_s=geometry_s,
        termination=solved.termination,
        std_error=std_error,
        undetermined=undetermined,
        rmse=float(np.sqrt(2 * final_loss / max(n_pixels, 1.0))),
        restarts=solved.restarts,
        light=fitted_light,
        initial_light=start.initial_light,
        alpha=fitted_alpha,
        initial_alpha=start.initial_alpha,
    )


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
