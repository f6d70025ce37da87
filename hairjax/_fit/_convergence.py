"""The solve loop (docs/fitting.md, "When a fit has converged"): the optimistix solver is
stepped until Gauss-Newton's predicted decrease confirms a stationary point; a solver whose
own test passes too early is restarted, one that stalls is tested, a plateau is left."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx

from ._solvers import NULL_RATIO
from ._space import entries

if TYPE_CHECKING:
    from ._options import FitStop

__all__ = [
    "MAX_RESTARTS",
    "STALL_STEPS",
    "stationarity",
    "state_stationarity",
    "half_square",
    "plateau_exit",
    "solve",
    "Solved",
    "init",
    "step",
    "state_loss",
    "terminate",
]

# `FitStop`'s defaults: how often `fit` starts a solver afresh when its tolerance test passed
# but the convergence test (`stationarity`) did not; and after how many steps without a lower
# loss it applies the convergence test itself (a trust region at the float32 floor rejects
# every step).
MAX_RESTARTS = 3
STALL_STEPS = 10


@eqx.filter_jit
def stationarity(residuals: Callable, z, problem):
    """(decrease, effect) at z for the residual function `residuals(z, problem)`.
    `decrease`: the loss a Gauss-Newton step from z would remove were the residuals linear,
    ½‖U_kᵀ r‖², U_k the left singular vectors of J = ∂r/∂z above NULL_RATIO (JΔ = −U_k U_kᵀ r
    for the least-squares step Δ). It is 0 exactly at a stationary point, whatever the
    solver's state; the solvers' own tests look at the last step's size instead, which a
    poor curvature estimate (BFGS) or a shrunken trust region makes small far from one.
    `effect`: ‖∂r/∂z_i‖ per entry of z."""
    r, jvp = jax.linearize(lambda z: residuals(z, problem), z)
    return _decrease(r, jax.vmap(jvp, out_axes=1)(jnp.eye(z.size, dtype=z.dtype)))


@eqx.filter_jit
def state_stationarity(state):
    """`stationarity` at a Gauss-Newton-family solver's current point from its state: the
    residuals there and their linearisation, kept by the step that evaluated them (only the
    Jacobian's tangent side runs, not the composite again)."""
    info = state.f_info
    return _decrease(info.residual, info.jac.as_matrix())


def _decrease(r, jac):
    """(½‖U_kᵀ r‖², the columns' norms) of residuals `r` and their Jacobian `jac` (`stationarity`)."""
    u, sv, _ = jnp.linalg.svd(jac, full_matrices=False)
    keep = sv > NULL_RATIO * sv[0]
    return 0.5 * jnp.sum(jnp.where(keep, u.T @ r, 0.0) ** 2), jnp.linalg.norm(jac, axis=0)


@eqx.filter_jit
def half_square(residuals: Callable, z, problem):
    """½‖r‖² at z for the residual function `residuals(z, problem)`."""
    return 0.5 * jnp.sum(residuals(z, problem) ** 2)


def plateau_exit(residuals: Callable, z, problem, effect, loss: float, rtol: float, atol: float):
    """From a stationary z on one of the model's plateaus (`FitModel.plateaus`: a fitted
    parameter without effect, ‖∂r/∂z_i‖ below NULL_RATIO of the largest column of J in each
    of its entries: e.g. Kajiya-Kay's shininess where Ks is solved to 0, or the highlight is
    a needle nowhere near a strand) — so every value of it is stationary and the solver can
    never leave — the z with the lowest loss over each such parameter's scan (taken through
    the parameter's transform; an RGB parameter's entries all set to each value), the
    plateaus tried in turn from the best z so far, if it beats `loss` beyond the tolerances;
    else None (also where no plateau applies: its parameter not fitted, or its gain not
    solved for). `problem`: a `_problem.Problem`."""
    model = problem.model
    best, best_loss = None, loss - (rtol * loss + atol)
    for plateau in model.plateaus:
        name = plateau.parameter
        if name not in problem.solved or (plateau.gain is not None and plateau.gain not in problem.linear):
            continue
        before = problem.solved[: problem.solved.index(name)]
        i = sum(entries(n, model.colours, problem.scalar, model.transforms) for n in before)
        k = entries(name, model.colours, problem.scalar, model.transforms)
        if not np.all(effect[i : i + k] <= NULL_RATIO * effect.max()):
            continue
        start = z if best is None else best
        candidates = [start.at[i : i + k].set(v) for v in _scan_in_z(model.transforms[name], plateau.scan)]
        losses = [float(half_square(residuals, c, problem)) for c in candidates]
        found = int(np.nanargmin(losses))
        if losses[found] < best_loss:
            best, best_loss = candidates[found], losses[found]
    return best


def _scan_in_z(transform, scan) -> list[float]:
    """A plateau's scan in the solver's space: the transform's inverse taken in float64
    whatever the fit's precision, so a float32 fit starts from each value's nearest float32
    (the inverse in float32 is an ulp off for some)."""
    with jax.enable_x64(True):
        return [float(transform.inverse(jnp.asarray(v, dtype=jnp.float64))) for v in scan]


# The solver's init, step and terminate, compiled once per solver, fn and shapes. (Within
# `init`, optimistix builds the state's static parts, e.g. a Jacobian's jaxpr compared by
# identity; compiled, they come back from the cache, so later fits hit it too.)
@eqx.filter_jit
def init(opt, fn, z, problem):
    f_struct, aux_struct = jax.eval_shape(lambda: fn(z, problem))
    return opt.init(fn, z, problem, {}, f_struct, aux_struct, frozenset())


@eqx.filter_jit
def step(opt, fn, z, problem, state):
    """(z, state, ½‖r‖² at z): one solver step and the loss at the point it returns, read
    off the solver's state rather than evaluated again (each evaluation composites every
    fragment). The solver returns its last accepted point; its state holds what `fn` gave
    there (`state_loss`)."""
    z, state, _ = opt.step(fn, z, problem, {}, state, frozenset())
    return z, state, state_loss(state)


def state_loss(state):
    """½‖r‖² at a solver's current point from its state: the Gauss-Newton family keeps
    the residuals (`FunctionInfo.ResidualJac`), BFGS the value of its `fn`, ½‖r‖²."""
    info = state.f_info
    if hasattr(info, "residual"):
        return 0.5 * jnp.sum(info.residual**2)
    return info.f


@eqx.filter_jit
def terminate(opt, fn, z, problem, state):
    return opt.terminate(fn, z, problem, {}, state, frozenset())


class Solved(NamedTuple):
    """What `solve` returns: the solver's last point `z` (a diverged solve's last finite
    one), the steps taken, why it stopped (`FitResult.termination`), the restarts, and
    whether the loss became non-finite."""

    z: Any
    steps: int
    termination: str
    restarts: int
    diverged: bool


def solve(
    opt,
    fn,
    residuals: Callable,
    z,
    problem,
    losses: list,
    *,
    stop: FitStop,
    report: Callable[[int, float], None],
    plateau: Callable | None = None,
) -> Solved:
    """Step the optimistix solver `opt` (on `fn`, whose residuals are `residuals(z,
    problem)`) from z until the convergence test confirms a stationary point, or it stops
    for a stated reason (`stop`, a `FitStop`). Appends each step's loss to `losses` and
    calls `report(step, loss)`. `plateau(z, effect, loss)`: a z to restart from where a
    parameter has no effect at a stationary point (or None).

    The convergence test (docs/fitting.md, "When a fit has converged"): Gauss-Newton's
    predicted decrease (`stationarity`) within rtol·loss + atol, the solver's tolerances.
    It is applied when the solver's own test passes (if it fails, the solver restarts from
    its point, at most `stop.max_restarts` times) and when no step has lowered the loss for
    `stop.stall_steps` steps."""
    rtol, atol = float(opt.rtol), float(opt.atol)
    steps, restarts, stalled, outcome = 0, 0, False, ""
    state = init(opt, fn, z, problem)
    done, result = terminate(opt, fn, z, problem, state)
    last_finite = z
    while True:
        if bool(done) and result != optx.RESULTS.successful:
            break
        if bool(done) or stalled:
            # After a step, losses[-1] is the loss at z (every change of z is a step's, or a
            # plateau's restart followed by a step); before the first, losses[0] is the
            # start's with its own gains, not z's with the gains solved for.
            loss = losses[-1] if steps else float(half_square(residuals, z, problem))
            last = restarts == stop.max_restarts
            verdict, z = _tested(state, residuals, z, problem, loss, bool(done), last, (rtol, atol), plateau)
            if verdict in ("converged", "unconfirmed"):
                outcome = verdict
                break
            if verdict == "restart":
                restarts += 1
                state = init(opt, fn, z, problem)
        if steps >= stop.max_steps:
            break
        z, state, loss = step(opt, fn, z, problem, state)
        steps += 1
        losses.append(float(loss))
        report(steps, losses[-1])
        if not np.isfinite(losses[-1]):
            # Fires for a solver that accepts every step (none of ours: trust regions and
            # Armijo reject a non-finite loss): stop, return the last finite point.
            z, outcome = last_finite, "diverged"
            break
        last_finite = z
        done, result = terminate(opt, fn, z, problem, state)
        stalled = _stalled(losses, steps, stop.stall_steps)
    return Solved(
        z=z,
        steps=steps,
        termination=_termination(outcome, bool(done), result, restarts, stop),
        restarts=restarts,
        diverged=outcome == "diverged",
    )


def _tested(state, residuals: Callable, z, problem, loss: float, done: bool, last: bool, tolerances, plateau):
    """The convergence test at z, whose loss is `loss`: ("converged", z) at a stationary
    point; ("restart", z') from a lower plateau's z' (`plateau`) or, where the solver's own
    test passed (`done`) away from a stationary point, from z itself (seen: BFGS with p
    still 4.5× off, its curvature estimate stale); ("unconfirmed", z) where that happens
    with no restart left (`last`); ("step", z) where a stalled solver is short of a
    stationary point. `tolerances`: the solver's (rtol, atol)."""
    rtol, atol = tolerances
    # Once it has stepped, a least-squares solver's state holds r and J at z (before,
    # `first_step`, its f_info is a placeholder).
    from_state = hasattr(state.f_info, "residual") and not bool(state.first_step)
    decrease, effect = state_stationarity(state) if from_state else stationarity(residuals, z, problem)
    if float(decrease) <= rtol * loss + atol:
        # A stationary point, unless a parameter has no effect there (`plateau`).
        lower = None if last or plateau is None else plateau(z, np.asarray(effect), loss)
        return ("converged", z) if lower is None else ("restart", lower)
    if done:
        return ("unconfirmed", z) if last else ("restart", z)
    return "step", z


def _stalled(losses: list, steps: int, stall_steps: int) -> bool:
    """No lower loss in the last `stall_steps` steps, checked every `stall_steps` steps (a
    trust region at the float32 floor rejects every step): the convergence test then says
    whether anything is left to gain."""
    recent = losses[-stall_steps - 1 :]
    return steps % stall_steps == 0 and len(recent) > stall_steps and min(recent[1:]) >= recent[0]


def _termination(outcome: str, done: bool, result, restarts: int, stop: FitStop) -> str:
    """`FitResult.termination` of a solve that ended with `outcome` ("converged",
    "unconfirmed", "diverged", or "" where the solver stopped or the steps ran out)."""
    if outcome == "diverged":
        return "stopped: diverged (the loss became non-finite); kept the last finite point"
    if outcome == "converged":
        return "converged"
    if outcome == "unconfirmed":
        return (
            f"stopped: the solver's tolerance test passed {restarts + 1} times where "
            "Gauss-Newton still predicts a decrease beyond the tolerances"
        )
    if done:
        return f"stopped: {optx.RESULTS[result]}"  # type: ignore[misc]  # equinox's enumeration: indexable at run time
    return f"stopped: reached max_steps = {stop.max_steps}"
