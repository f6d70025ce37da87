"""The solvers `fit` steps (docs/fitting.md, "Gauss-Newton" and "BFGS"), as optimistix
solver objects: optimistix's `LevenbergMarquardt` (the default) and `Dogleg`, and two of
ours, `GaussNewton` (damped: Armijo backtracking) and `BFGS` (on ½‖r‖², with a scaled
first step). `fit(solver=...)` takes any of them, or any optimistix least-squares solver or
minimiser; the tolerances are the solver's. `fit_solvers()` builds the four by name, with the
working precision's tolerances: the CLI's `--solver` and the experiments read it. Equal
solvers compare equal, so compiled steps are reused across fits."""

from __future__ import annotations

from collections.abc import Callable

import jax.numpy as jnp
import lineax as lx
import optimistix as optx

from ._result import FitError

__all__ = [
    "SOLVERS",
    "ALIASES",
    "NULL_RATIO",
    "GaussNewton",
    "BFGS",
    "default_tolerances",
    "fit_solvers",
    "solver_named",
    "is_least_squares",
]

SOLVERS = ("levenberg-marquardt", "gauss-newton", "dogleg", "bfgs")
ALIASES = {"lm": "levenberg-marquardt", "gn": "gauss-newton"}
# A direction of J whose singular value is below NULL_RATIO of the largest is taken as
# without effect, in the solvers' steps and in the standard errors alike: far above the
# rounding of an SVD in float32 (~1e-7), far below any effect the data resolve.
NULL_RATIO = 1e-5
# A parameter with no effect (p when Ks = 0) leaves a zero column in J: Gauss-Newton's and
# dogleg's default solve then returned NaN or never moved. Least squares through an SVD
# takes the minimum-norm step instead; LM's damping needs none. Its cutoff is ours:
# lineax's default, 2·eps·max(m, n) of the largest singular value, is 3.6 % with 150k
# float32 residuals; it dropped a faint highlight's shininess from every step, and both
# solvers "converged" at the start's p (Ks 48 %, p 90 % off on fit_recovery's set 0).
RANK_DEFICIENT = lx.SVD(rcond=NULL_RATIO)


def default_tolerances() -> tuple[float, float]:
    """(rtol, atol) of the working precision: 1e-8 and 1e-10 in float64, 1e-5 and 1e-7 in
    float32 (tighter than float32 resolves only adds steps that change nothing)."""
    double = jnp.result_type(float) == jnp.float64
    return (1e-8, 1e-10) if double else (1e-5, 1e-7)


def fit_solvers(rtol: float | None = None, atol: float | None = None) -> dict:
    """The four solvers `fit` is tested with, by name (`SOLVERS`), with these tolerances
    (default `default_tolerances()`)."""
    d_rtol, d_atol = default_tolerances()
    rtol = d_rtol if rtol is None else rtol
    atol = d_atol if atol is None else atol
    return {
        "levenberg-marquardt": optx.LevenbergMarquardt(rtol=rtol, atol=atol),
        "gauss-newton": GaussNewton(rtol=rtol, atol=atol),
        "dogleg": optx.Dogleg(rtol=rtol, atol=atol, linear_solver=RANK_DEFICIENT),
        "bfgs": BFGS(rtol=rtol, atol=atol),
    }


def solver_named(name: str, rtol: float | None = None, atol: float | None = None):
    """`fit_solvers()[name]`, `name` a name of `SOLVERS` or an alias (`ALIASES`); FitError for
    an unknown name (the CLI's `--solver`)."""
    made = fit_solvers(rtol, atol)
    name = ALIASES.get(name, name)
    if name not in made:
        raise FitError(f"unknown solver {name!r}; choose from {', '.join(SOLVERS)} (or lm, gn)")
    return made[name]


def is_least_squares(solver) -> bool:
    """Whether `solver` is an optimistix least-squares solver (it is given the residuals),
    else a minimiser (given ½‖r‖²); FitError for anything else."""
    if isinstance(solver, optx.AbstractLeastSquaresSolver):
        return True
    if isinstance(solver, optx.AbstractMinimiser):
        return False
    raise FitError(
        "solver must be an optimistix least-squares solver or minimiser (e.g. "
        f"optimistix.LevenbergMarquardt(rtol=1e-5, atol=1e-7), hairjax.GaussNewton), got {solver!r}"
    )


def _quiet(*args, **kwargs) -> None:
    """optimistix's `verbose` hook: `fit` reports progress itself."""


class GaussNewton(optx.AbstractGaussNewton):
    """Gauss-Newton steps with Armijo backtracking (Nocedal & Wright 2006, §10.3, "damped
    Gauss-Newton") instead of optimistix's full steps (`LearningRate(1.0)`), solved through
    an SVD (`RANK_DEFICIENT`). From a start 100 times too low a full step raised κ from
    0.02 to 4e7 and the loss from 57 to 159: every strand then lies in shadow, κ has no
    effect, and the solver "converged" there."""

    rtol: float
    atol: float
    norm: Callable = optx.max_norm
    descent: optx.AbstractDescent = optx.NewtonDescent(linear_solver=RANK_DEFICIENT)
    search: optx.AbstractSearch = optx.BacktrackingArmijo()
    verbose: Callable = _quiet


def _operator(matrix):
    return lx.MatrixLinearOperator(matrix, lx.positive_semidefinite_tag)


class BFGS(optx.AbstractBFGS):
    """BFGS on ½‖r‖² over a flat z (docs/fitting.md, "BFGS"): optimistix's quasi-Newton
    step and Armijo backtracking, with the initial Hessian scaled as Nocedal & Wright
    (2006, §6.1) advise instead of left at the identity, and a scale-free test for skipping
    an update. Both matter here:
    - With H₀ = I the first step is −∇f, which grows with the pixel count; it threw a faint
      Ks deep into the softplus's flat tail, where its gradient vanishes, and BFGS
      "converged" with Ks = 0. Here the first step is −∇f/‖∇f‖ (unit length in z: one
      e-fold of p or κ), and before the first update H is reset to (yᵀy / sᵀy)·I.
    - optimistix updates only when sᵀy > ε (absolute). In float32 sᵀy falls below 1.2e-7
      near the optimum of a small loss, every update was skipped and BFGS crawled on a stale
      Hessian; here the test is sᵀy > ε‖s‖‖y‖."""

    rtol: float
    atol: float
    norm: Callable = optx.max_norm
    use_inverse: bool = False
    descent: optx.AbstractDescent = optx.NewtonDescent(linear_solver=lx.Cholesky())
    search: optx.AbstractSearch = optx.BacktrackingArmijo()
    verbose: Callable = _quiet

    def init_hessian(self, y, f, grad):
        # The state counts the updates made: 0 before the first step, 1 before the first
        # (s, y) pair.
        eye = jnp.eye(y.size, dtype=y.dtype)
        return optx.FunctionInfo.EvalGradHessian(f, grad, _operator(eye)), jnp.array(0)

    def update_hessian(self, y, y_eval, f_info, f_eval_info, count):
        g = f_eval_info.grad
        s, dg = y_eval - y, g - f_info.grad
        sy, yy = s @ dg, dg @ dg
        # Fires when sᵀy is not positive beyond rounding (on the first step s = 0, or the
        # curvature condition fails and the update would make H indefinite): keep H.
        ok = sy > jnp.finfo(sy.dtype).eps * jnp.linalg.norm(s) * jnp.sqrt(yy)
        sy_safe = jnp.where(ok, sy, 1.0)  # fires with `ok` false: the value is unused
        g_norm = jnp.linalg.norm(g)
        g_norm = jnp.where(g_norm > 0, g_norm, 1.0)  # fires for a start at a stationary point
        # H before this update: ‖g‖·I on the first step (a unit first step), (yᵀy/sᵀy)·I at
        # the first (s, y) pair, else the running approximation.
        previous = f_info.hessian.as_matrix()
        scale = jnp.where(count == 0, g_norm, yy / sy_safe)
        h = jnp.where(count <= 1, scale * jnp.eye(y.size, dtype=y.dtype), previous)
        hs = h @ s
        shs = s @ hs
        # shs > 0 whenever ok (h is positive definite and s ≠ 0); guarded all the same.
        update = ok & (shs > 0)
        shs_safe = jnp.where(update, shs, 1.0)
        updated = h + jnp.outer(dg, dg) / sy_safe - jnp.outer(hs, hs) / shs_safe
        h = jnp.where(update, updated, jnp.where(count == 0, h, previous))
        info = optx.FunctionInfo.EvalGradHessian(f_eval_info.f, g, _operator(h))
        return info, count + jnp.where((count == 0) | ok, 1, 0)
