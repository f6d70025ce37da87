"""The solvers `fit` steps (docs/fitting.md, "Gauss-Newton" and "BFGS"): optimistix's
Levenberg-Marquardt and dogleg, Gauss-Newton with Armijo backtracking, and BFGS on ½‖r‖²
with a scaled first step; each built once per tolerance pair, so compiled steps are reused."""

from __future__ import annotations

import functools
from collections.abc import Callable

import jax.numpy as jnp

from ._result import FitError

__all__ = ["SOLVERS", "ALIASES", "NULL_RATIO", "make_solver", "damped_gauss_newton", "bfgs"]

SOLVERS = ("levenberg-marquardt", "gauss-newton", "dogleg", "bfgs")
ALIASES = {"lm": "levenberg-marquardt", "gn": "gauss-newton"}
# A direction of J whose singular value is below NULL_RATIO of the largest is taken as
# without effect, in the solvers' steps and in the standard errors alike: far above the
# rounding of an SVD in float32 (~1e-7), far below any effect the data resolve.
NULL_RATIO = 1e-5


def make_solver(name: str, rtol: float, atol: float):
    """(the optimistix solver called `name` or its alias, whether it is a least-squares
    solver (else a minimiser of ½‖r‖²)); FitError for an unknown name."""
    import lineax as lx
    import optimistix as optx

    name = ALIASES.get(name, name)
    if name == "levenberg-marquardt":
        return optx.LevenbergMarquardt(rtol=rtol, atol=atol), True
    # A parameter with no effect (p when Ks = 0) leaves a zero column in J: Gauss-Newton's
    # and dogleg's default solve then returned NaN or never moved. Least squares through an
    # SVD takes the minimum-norm step instead; LM's damping needs none. Its cutoff is ours:
    # lineax's default, 2·eps·max(m, n) of the largest singular value, is 3.6 % with 150k
    # float32 residuals; it dropped a faint highlight's shininess from every step, and both
    # solvers "converged" at the start's p (Ks 48 %, p 90 % off on fit_recovery's set 0).
    rank_deficient = lx.SVD(rcond=NULL_RATIO)
    if name == "gauss-newton":
        return damped_gauss_newton(rtol, atol, rank_deficient), True
    if name == "dogleg":
        return optx.Dogleg(rtol=rtol, atol=atol, linear_solver=rank_deficient), True
    if name == "bfgs":
        return bfgs(rtol, atol), False
    raise FitError(f"unknown solver {name!r}; choose from {', '.join(SOLVERS)} (or lm, gn)")


def _quiet(*args, **kwargs) -> None:
    """optimistix's `verbose` hook: `fit` reports progress itself."""


# Cached, so that every fit gets the same solver class and its compiled steps are reused.
@functools.cache
def damped_gauss_newton(rtol: float, atol: float, linear_solver):
    """Gauss-Newton steps with Armijo backtracking (Nocedal & Wright 2006, §10.3, "damped
    Gauss-Newton") instead of optimistix's full steps (`LearningRate(1.0)`). From a start
    100 times too low a full step raised κ from 0.02 to 4e7 and the loss from 57 to 159:
    every strand then lies in shadow, κ has no effect, and the solver "converged" there."""
    import optimistix as optx

    class _GaussNewton(optx.AbstractGaussNewton):
        rtol: float
        atol: float
        descent: optx.AbstractDescent = optx.NewtonDescent()  # replaced: the SVD solve below
        norm: Callable = optx.max_norm
        search: optx.AbstractSearch = optx.BacktrackingArmijo()
        verbose: Callable = _quiet

    return _GaussNewton(rtol=rtol, atol=atol, descent=optx.NewtonDescent(linear_solver=linear_solver))


@functools.cache  # as damped_gauss_newton
def bfgs(rtol: float, atol: float):
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
    import lineax as lx
    import optimistix as optx

    def operator(matrix):
        return lx.MatrixLinearOperator(matrix, lx.positive_semidefinite_tag)

    class _BFGS(optx.AbstractBFGS):
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
            return optx.FunctionInfo.EvalGradHessian(f, grad, operator(eye)), jnp.array(0)

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
            info = optx.FunctionInfo.EvalGradHessian(f_eval_info.f, g, operator(h))
            return info, count + jnp.where((count == 0) | ok, 1, 0)

    return _BFGS(rtol=rtol, atol=atol)
