"""`hairjax.fit` for Scheuermann scenes (docs/model.md §17, docs/fitting.md).

The Kajiya-Kay fit (`_entry.py`) is built on that model's terms: Kd and Ks solved for by
variable projection, b precomputed per point. Here the solver iterates on every fitted
parameter through the differentiable shading stage; the geometry stage runs once per
target. Colours are fitted through a softplus (≥ 0), exponents and κ through exp
(scale-free, > 0), shifts as they are.
"""

from __future__ import annotations

import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._render import geometry_stage, shading_stage
from .._scheuermann import ScheuermannParams
from ._convergence import half_square, solve
from ._result import FitError, FitResult
from ._space import IDENTITY, LOG, SOFTPLUS, entries, error_space, from_flat, to_flat
from ._uncertainty import covariance

__all__ = ["SCHEUERMANN_FITTABLE", "fit_scheuermann"]

SCHEUERMANN_FITTABLE = ("kd", "primary_color", "primary_exponent", "primary_shift",
                        "secondary_color", "secondary_exponent", "secondary_shift", "kappa")
_COLOURS = ("kd", "primary_color", "secondary_color")


# The solver's space: colours through a softplus (≥ 0), exponents and κ through exp
# (scale-free, > 0), shifts as they are; the standard errors in `error_space` of it.
_TRANSFORMS = {**{n: SOFTPLUS for n in _COLOURS},
               **{n: LOG for n in ("primary_exponent", "secondary_exponent", "kappa")},
               **{n: IDENTITY for n in ("primary_shift", "secondary_shift")}}


def check_names(names, scalar) -> tuple[str, ...]:
    names = tuple(names)
    for n in (*names, *scalar):
        if n not in SCHEUERMANN_FITTABLE:
            raise FitError(f"unknown parameter {n!r} for a Scheuermann scene; fittable: "
                           f"{', '.join(SCHEUERMANN_FITTABLE)}")
    if len(set(names)) != len(names) or not names:
        raise FitError(f"fit needs distinct parameter names, got {names!r}")
    for n in scalar:
        if n not in _COLOURS:
            raise FitError(f"only {', '.join(_COLOURS)} can be fitted as one grey value, not {n!r}")
    return names


class _Problem(eqx.Module):
    geometries: list
    targets: list
    sqrt_weights: list
    init: ScheuermannParams
    names: tuple[str, ...] = eqx.field(static=True)
    scalar: tuple[str, ...] = eqx.field(static=True)


def _residuals_at(p: ScheuermannParams, problem: _Problem) -> jax.Array:
    r = [sw * (shading_stage(g, p)[..., :3].reshape(-1, 3) - t)
         for g, t, sw in zip(problem.geometries, problem.targets, problem.sqrt_weights)]
    return jnp.concatenate([x.ravel() for x in r])


def _residuals(z, problem: _Problem) -> jax.Array:
    return _residuals_at(from_flat(z, problem.init, problem.names, _COLOURS, problem.scalar, _TRANSFORMS),
                         problem)


def _residual_fn(z, problem):
    return _residuals(z, problem), None


def _loss_fn(z, problem):
    return 0.5 * jnp.sum(_residuals(z, problem) ** 2), None


def fit_scheuermann(scenes, arrays, names, init, opt, least_squares, scalar, max_steps,
                    rtol, atol, progress) -> FitResult:
    """`hairjax.fit` for Scheuermann scenes: `arrays` are `_target_arrays`' (target,
    √weight) per scene, `names` checked by `check_names`; the rest as `fit` passes them."""
    if not isinstance(init, ScheuermannParams):
        raise FitError(f"a Scheuermann scene is fitted from ScheuermannParams, got {type(init).__name__}")
    scalar = tuple(scalar)
    start = time.perf_counter()
    geometries = [geometry_stage(s) for s in scenes]
    jax.block_until_ready(geometries)
    geometry_s = time.perf_counter() - start
    problem = _Problem(geometries, [jnp.asarray(t) for t, _ in arrays],
                       [jnp.asarray(sw) for _, sw in arrays], init, names, scalar)
    z = to_flat(init, names, scalar, _TRANSFORMS)
    fn = _residual_fn if least_squares else _loss_fn
    losses = [float(0.5 * jnp.sum(_residuals_at(init, problem) ** 2))]

    def report(step, loss):
        if progress is not None:
            progress(step, loss, time.perf_counter() - start - geometry_s)

    z, steps, termination, restarts, diverged = solve(
        opt, fn, _residuals, z, problem, losses, max_steps=max_steps, rtol=rtol, atol=atol,
        report=report)
    fitted = from_flat(z, init, names, _COLOURS, scalar, _TRANSFORMS)
    elapsed = time.perf_counter() - start - geometry_s
    std_error, undetermined = _standard_errors(fitted, problem)
    n_pixels = float(sum(np.count_nonzero(np.asarray(sw)) for _, sw in arrays)) * 3
    final_loss = float(half_square(_residuals, z, problem)) if diverged else losses[-1]
    return FitResult(params=fitted, initial=init, fitted=names, loss=losses, steps=steps,
                     time_s=elapsed, geometry_s=geometry_s, termination=termination,
                     std_error=std_error, undetermined=undetermined,
                     rmse=float(np.sqrt(2 * final_loss / max(n_pixels, 1.0))), restarts=restarts)


@eqx.filter_jit
def _error_jacobian(u, fitted, problem: _Problem):
    def residuals(u):
        return _residuals_at(from_flat(u, fitted, problem.names, _COLOURS, problem.scalar,
                                       error_space(_TRANSFORMS)), problem)

    return jax.jacfwd(residuals)(u), residuals(u)


def _standard_errors(fitted: ScheuermannParams, problem: _Problem):
    """σ²(JᵀJ)⁻¹ in the error space, mapped to the parameters (delta method); undetermined
    directions as `_uncertainty.covariance` decides them."""
    names, scalar = problem.names, problem.scalar
    space = error_space(_TRANSFORMS)
    u = to_flat(fitted, names, scalar, space)
    cov = covariance(*_error_jacobian(u, fitted, problem))
    if cov is None:
        return {n: None for n in names}, names
    var_u, in_null = cov
    std, undetermined, i = {}, [], 0
    u = np.asarray(u)
    for n in names:
        sl = slice(i, i + entries(n, _COLOURS, scalar))
        i = sl.stop
        if in_null[sl].any():
            std[n] = None
            undetermined.append(n)
            continue
        # dx/du: 1 for colours and shifts, x for the log-space exponents and κ.
        dxdu = np.exp(u[sl]) if space[n].forward is jnp.exp else np.ones(sl.stop - sl.start)
        value = dxdu * np.sqrt(np.maximum(var_u[sl], 0.0))
        std[n] = np.broadcast_to(value, (3,)).copy() if n in _COLOURS else np.asarray(value[0])
    return std, tuple(undetermined)
