"""Fitting Kd, Ks, shininess and κ to target images with optimistix (docs/fitting.md).

The image is linear in Kd, Ks and the ambient term:

    image = ambient⊙A + Kd⊙K_d(κ) + Ks⊙K_s(κ, p) + T·backdrop + T·O(κ),

A = composite(c), K_d = composite(τ·light·sin(T, L)·c), K_s = composite(τ·light·b^p)
(docs/model.md §6, §8); with an occluder, the backdrop is 0 at the pixels it covers and
O(κ) = k·ambient + exp(−κΩ)·V·k·light·max(N·L, 0) there (§13, `occluder_colors`). The geometry stage
runs once per target; Kajiya-Kay's geometric terms once per target; K_d is recomputed per
step only when κ is fitted, K_s only when κ or the shininess is, and otherwise a step is a
handful of per-pixel multiply-adds. Being
linear, the fitted gains are by default solved for (non-negative least squares) at every
step, and the solver iterates on the shininess and κ only (variable projection).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._scene import Scene
from .._shading import ShadingParams
from ._convergence import half_square, solve
from ._kajiya_kay import TargetTerms, fixed_image, image, kd_ks_images, prepare_terms
from ._nnls import nnls
from ._problem import target_arrays
from ._result import FitError, FitResult
from ._solvers import NULL_RATIO, SOLVERS, make_solver
from ._space import LOG, SOFTPLUS, error_space, from_flat, to_flat, unflatten, with_values
from ._uncertainty import covariance

__all__ = ["fit", "FITTABLE", "SOLVERS"]

FITTABLE = ("kd", "ks", "shininess", "kappa")


# The solver's space (docs/fitting.md): softplus for the colour gains, log for the
# scale-free exponent and extinction.
_TRANSFORMS = {"kd": SOFTPLUS, "ks": SOFTPLUS, "shininess": LOG, "kappa": LOG}
# Where `fit` looks for a lower loss when it stops with every solved Ks at 0 (p then has no
# effect): the shininess on a log grid over the range we support, 1.5× apart.
_SHININESS_SCAN = tuple(float(p) for p in np.geomspace(0.5, 1e4, 25))


def _check_names(fit_names, scalar) -> tuple[str, ...]:
    names = tuple(fit_names)
    for n in (*names, *scalar):
        if n not in FITTABLE:
            raise FitError(f"unknown parameter {n!r}; fittable: {', '.join(FITTABLE)}")
    if len(set(names)) != len(names) or not names:
        raise FitError(f"fit needs distinct parameter names, got {names!r}")
    for n in scalar:
        if n not in ("kd", "ks"):
            raise FitError(f"only kd and ks can be fitted as one grey value, not {n!r}")
    return names


# Kd and Ks enter the image linearly (module docstring): with `separable`, `fit` solves
# whichever of them are fitted by non-negative linear least squares at every step
# (variable projection, Golub & Pereyra 1973) and the solver iterates on p and κ only.
_LINEAR = ("kd", "ks")


def _design(terms: TargetTerms, linear, scalar, params: ShadingParams, shininess, kappa):
    """One target's least-squares problem in the linear unknowns: Φ `[HW·3, n]` (a column
    per fitted Kd/Ks channel, or one for a grey value) and the right-hand side `[HW·3]`,
    both weighted, so that the residuals are Φc − rhs."""
    kd_image, ks_image = kd_ks_images(terms, shininess, kappa)
    fixed = fixed_image(terms, kappa)
    columns = []
    for name, gain_image in (("kd", kd_image), ("ks", ks_image)):
        if name not in linear:
            fixed = fixed + getattr(params, name)[None, :] * gain_image
        elif name in scalar:
            columns.append(gain_image)
        else:
            columns.extend(gain_image * jnp.eye(3, dtype=gain_image.dtype)[None, c] for c in range(3))
    sw = terms.sqrt_weight
    phi = jnp.stack([(sw * c).ravel() for c in columns], axis=1)
    return phi, (sw * (terms.target - fixed)).ravel()


def _unpack_linear(c: jax.Array, linear, scalar) -> dict:
    """The coefficient vector of `_design`'s columns as RGB Kd / Ks values."""
    out, i = {}, 0
    for name in linear:
        k = 1 if name in scalar else 3
        out[name] = jnp.broadcast_to(c[i:i + k], (3,))
        i += k
    return out


class _Problem(eqx.Module):
    """Everything a solver step needs besides z: the targets' terms and the held values
    (arrays), and which names the solver searches and which gains are solved for (static).
    The functions below are module-level and take it as `args`, so a compiled step is
    reused by every fit with the same shapes and names."""

    terms: list
    init: ShadingParams
    solved: tuple[str, ...] = eqx.field(static=True)
    linear: tuple[str, ...] = eqx.field(static=True)
    scalar: tuple[str, ...] = eqx.field(static=True)


def _point(z, problem: _Problem):
    """The parameters at the solver's z (the gains in `problem.linear` solved for) and the
    residuals there, flat."""
    p = from_flat(z, problem.init, problem.solved, _LINEAR, problem.scalar, _TRANSFORMS)
    if not problem.linear:
        return p, _plain_residuals(p, problem.terms)
    systems = [_design(t, problem.linear, problem.scalar, p, p.shininess, p.kappa)
               for t in problem.terms]
    phi = jnp.concatenate([a for a, _ in systems])
    rhs = jnp.concatenate([b for _, b in systems])
    c = nnls(phi, rhs)
    return with_values(p, _unpack_linear(c, problem.linear, problem.scalar), _LINEAR), phi @ c - rhs


def _residuals(z, problem: _Problem):
    """The weighted residuals at the solver's z, flat."""
    return _point(z, problem)[1]


def _loss(z, problem: _Problem):
    return 0.5 * jnp.sum(_residuals(z, problem) ** 2)


def _residual_fn(z, problem: _Problem):
    """optimistix's least-squares `fn`: (residuals, aux)."""
    return _point(z, problem)[1], None


def _loss_fn(z, problem: _Problem):
    """optimistix's minimiser `fn` (BFGS): (½‖r‖², aux)."""
    return _loss(z, problem), None


def _plateau_exit(z, problem: _Problem, effect, loss: float, rtol: float, atol: float):
    """From a stationary z where the shininess has no effect (‖∂r/∂log p‖ below NULL_RATIO
    of the largest column of J: the solved Ks is 0, or the highlight is a needle nowhere
    near a strand) — so every p is stationary and the solver can never leave — the z with
    the shininess of `_SHININESS_SCAN` whose loss is lowest, if it beats `loss` beyond the
    tolerances; else None (also when Ks is not solved for, or p not fitted)."""
    if "ks" not in problem.linear or "shininess" not in problem.solved:
        return None
    i = problem.solved.index("shininess")  # scalar entries only precede it (gains are solved)
    if not effect[i] <= NULL_RATIO * effect.max():
        return None
    candidates = [z.at[i].set(np.log(p)) for p in _SHININESS_SCAN]
    losses = [float(_jit_loss(c, problem)) for c in candidates]
    best = int(np.nanargmin(losses))
    return candidates[best] if losses[best] < loss - (rtol * loss + atol) else None


_jit_point = eqx.filter_jit(_point)


def _jit_loss(z, problem: _Problem):
    """½‖r‖² at z, compiled (the same function as `solve`'s losses)."""
    return half_square(_residuals, z, problem)


@eqx.filter_jit
def _jit_plain_loss(p: ShadingParams, terms):
    return 0.5 * jnp.sum(_plain_residuals(p, terms) ** 2)


def fit(
    scene: Scene | Sequence[Scene],
    targets,
    fit: Sequence[str] = FITTABLE,
    init: ShadingParams | None = None,
    solver: str = "levenberg-marquardt",
    *,
    masks=None,
    weights=None,
    scalar: Sequence[str] = (),
    max_steps: int = 100,
    separable: bool = True,
    rtol: float | None = None,
    atol: float | None = None,
    progress: Callable[[int, float, float], None] | None = None,
) -> FitResult:
    """Least-squares fit of shading parameters to one or more target images.

    **Arguments:**
    - `scene`: a Scene, or one per target (the same hair under several views or lights).
    - `targets`: an `[H, W, 3|4]` linear image, or a list of them (alpha is ignored).
    - `fit`: names among kd, ks, shininess, kappa; the rest stay at `init`. For a
      Scheuermann scene (docs/model.md §17): among kd, primary_color, primary_exponent,
      primary_shift, secondary_color, secondary_exponent, secondary_shift, kappa (default:
      all), fitted by the solver directly (`separable` does not apply).
    - `init`: starting (and fixed) parameters, default the first scene's.
    - `solver`: levenberg-marquardt (lm), gauss-newton, dogleg, or bfgs (on ½‖r‖²).
    - `masks`, `weights`: optional per-target `[H, W]` pixel masks and weights.
    - `scalar`: among kd, ks, those fitted as one grey value instead of RGB.
    - `separable`: solve the fitted Kd, Ks by non-negative linear least squares at every
      step (variable projection; the image is linear in them) so that the solver iterates
      on shininess and κ only; a fit of gains alone is then one solve. False: the solver
      iterates on every fitted parameter (docs/fitting.md).
    - `rtol`, `atol`: the solver's tolerances; default 1e-8 and 1e-10 in float64, 1e-5 and
      1e-7 in float32 (tighter than float32 resolves only adds steps that change nothing).
    - `progress(step, loss, elapsed_s)`: called after every step.

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
    scheuermann = any(s.shading_model == "scheuermann" for s in scenes)  # docs/model.md §17
    names = _scheuermann_names(scenes, fit, scalar) if scheuermann else _check_names(fit, scalar)
    double = jnp.result_type(float) == jnp.float64
    rtol = (1e-8 if double else 1e-5) if rtol is None else rtol
    atol = (1e-10 if double else 1e-7) if atol is None else atol
    opt, least_squares = make_solver(solver, rtol, atol)
    init = scenes[0].params if init is None else init
    arrays = [target_arrays(s, t, m, w) for s, t, m, w in zip(scenes, target_list, mask_list, weight_list)]
    if scheuermann:
        from ._scheuermann import fit_scheuermann

        return fit_scheuermann(scenes, arrays, names, init, opt, least_squares, scalar, max_steps,
                               rtol, atol, progress)

    start = time.perf_counter()
    terms = [prepare_terms(s, init, names, t, sw) for s, (t, sw) in zip(scenes, arrays)]
    jax.block_until_ready(terms)
    geometry_s = time.perf_counter() - start

    # The solver iterates on z over `solved`; the fitted gains in `linear` are solved for.
    linear = tuple(n for n in _LINEAR if separable and n in names)
    solved = tuple(n for n in names if n not in linear)
    problem = _Problem(terms, init, solved, linear, tuple(scalar))
    z = to_flat(init, solved, scalar, _TRANSFORMS)
    fn = _residual_fn if least_squares else _loss_fn
    # loss[0] is the loss at `init` itself, its gains included (not at the solved gains).
    losses = [float(_jit_plain_loss(init, terms))]

    def report(step, loss):
        if progress is not None:
            progress(step, loss, time.perf_counter() - start - geometry_s)

    if not solved:
        # Only gains are fitted: one linear least-squares solve is the whole fit.
        steps, termination, restarts, diverged = 1, "converged", 0, False
        losses.append(float(_jit_loss(z, problem)))
        report(steps, losses[-1])
    else:
        z, steps, termination, restarts, diverged = solve(
            opt, fn, _residuals, z, problem, losses, max_steps=max_steps, rtol=rtol, atol=atol,
            report=report, plateau=lambda z, effect, loss: _plateau_exit(z, problem, effect, loss,
                                                                         rtol, atol))
    fitted = _jit_point(z, problem)[0]
    elapsed = time.perf_counter() - start - geometry_s

    std_error, undetermined = _standard_errors(terms, fitted, names, scalar)
    n_pixels = float(sum(np.count_nonzero(np.asarray(t.sqrt_weight)) for t in terms)) * 3
    final_loss = float(_jit_loss(z, problem)) if diverged else losses[-1]  # at the returned point
    rmse = float(np.sqrt(2 * final_loss / max(n_pixels, 1.0)))
    return FitResult(params=fitted, initial=init, fitted=names, loss=losses, steps=steps,
                     time_s=elapsed, geometry_s=geometry_s, termination=termination,
                     std_error=std_error, undetermined=undetermined, rmse=rmse, restarts=restarts)


def _scheuermann_names(scenes, names, scalar) -> tuple[str, ...]:
    """The names a Scheuermann fit takes (`_scheuermann.py`; every scene must be one):
    FITTABLE, `fit`'s default, stands for all of that model's parameters."""
    from ._scheuermann import SCHEUERMANN_FITTABLE, check_names

    if any(s.shading_model != "scheuermann" for s in scenes):
        raise FitError("scenes of one fit share a shading model; got Scheuermann and Kajiya-Kay")
    return check_names(SCHEUERMANN_FITTABLE if names is FITTABLE else names, scalar)


def _plain_residuals(p: ShadingParams, terms) -> jax.Array:
    """The weighted residuals of all targets at `p`, flat."""
    r = [t.sqrt_weight * (image(t, p.kd, p.ks, p.shininess, p.kappa) - t.target) for t in terms]
    return jnp.concatenate([x.ravel() for x in r])


@eqx.filter_jit
def _error_jacobian(u, fitted: ShadingParams, terms, names, scalar):
    """J and r of the residuals in the standard errors' space (`error_space`) at u."""

    def residuals(u):
        return _plain_residuals(from_flat(u, fitted, names, _LINEAR, scalar, error_space(_TRANSFORMS)),
                                terms)

    return jax.jacfwd(residuals)(u), residuals(u)


def _standard_errors(terms, fitted: ShadingParams, names, scalar):
    """Standard errors from σ²(JᵀJ)⁻¹, J taken in the gains Kd, Ks and in log p, log κ,
    mapped to the parameters by the transforms' derivatives (delta method). Parameters
    with weight in a direction the data do not determine (`covariance`: one unit along it,
    an e-fold of shininess or κ or a unit of gain, moves the residuals by under 1e-6 RMS, or
    it is numerically singular) get no error."""
    space = error_space(_TRANSFORMS)
    flat = to_flat(fitted, names, scalar, space)
    cov = covariance(*_error_jacobian(flat, fitted, terms, tuple(names), tuple(scalar)))
    if cov is None:
        return {name: None for name in names}, tuple(names)
    var_u, in_null = cov
    u = unflatten(flat, names, _LINEAR, scalar)
    std, undetermined, i = {}, [], 0
    for name in names:
        size = int(np.size(u[name]))
        sl, i = slice(i, i + size), i + size
        if in_null[sl].any():
            std[name] = None
            undetermined.append(name)
            continue
        dxdu = np.asarray(jax.vmap(jax.grad(space[name].forward))(u[name]))
        se = np.abs(dxdu) * np.sqrt(np.maximum(var_u[sl], 0.0))
        std[name] = se if size > 1 else float(se[0])
    return std, tuple(undetermined)
