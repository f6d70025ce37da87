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

from .._constants import FIT_TRANSMITTANCE_CUTOFF
from .._lookup import LOOKUP_MODELS, lookup_coordinates, lookup_terms
from .._render import composite, geometry_stage, occluder_colors
from .._scene import Scene
from .._shading import ShadingParams, kajiya_kay_terms, specular_power
from ._convergence import half_square, solve
from ._nnls import nnls
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


class _Terms(eqx.Module):
    """Per target, everything a step needs that no fitted parameter reaches."""

    geometry: object
    sin_tl: jax.Array
    gap: jax.Array  # 1 − b per point (Kajiya-Kay, docs/model.md §8)
    lit_color: jax.Array  # light · c per point
    light: jax.Array
    omega: jax.Array | None
    constant: jax.Array  # ambient⊙A + T·backdrop, [HW, 3]
    ambient: jax.Array  # the held ambient, for the occluder's colour (§13)
    kd_image: jax.Array | None  # K_d when κ is fixed
    ks_image: jax.Array | None  # K_s when κ and p are fixed
    target: jax.Array
    sqrt_weight: jax.Array
    # Lookup models (§14): per point (u, v) and where the terms are lit; `gap` is then unused.
    lookup: tuple | None = None
    lookup_size: int = eqx.field(static=True, default=0)
    model: str = eqx.field(static=True, default="kajiya-kay")


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


def _target_arrays(scene: Scene, target, mask, weight):
    h, w = scene.camera.height, scene.camera.width
    image = np.asarray(target, dtype=np.float64)
    if image.ndim != 3 or image.shape[2] < 3:
        raise FitError(f"target for {scene.name!r} must be [H, W, 3 or 4], got {image.shape}")
    if image.shape[:2] != (h, w):
        raise FitError(f"target is {image.shape[1]}x{image.shape[0]} but scene {scene.name!r} "
                       f"renders {w}x{h}")
    if not np.all(np.isfinite(image[..., :3])):
        raise FitError(f"target for {scene.name!r} has NaN or infinite pixels")
    wt = np.ones((h, w)) if weight is None else np.broadcast_to(np.asarray(weight, float), (h, w))
    if mask is not None:
        wt = wt * (np.broadcast_to(np.asarray(mask), (h, w)) > 0)
    if not np.all(np.isfinite(wt)) or np.any(wt < 0):
        raise FitError("weights must be finite and non-negative")
    return image[..., :3].reshape(-1, 3), np.sqrt(wt).reshape(-1, 1)


def _visible_fragments(geom):
    """The geometry without fragments behind transmittance < FIT_TRANSMITTANCE_CUTOFF
    (their total weight per pixel is below the cutoff: see hairjax/_constants.py)."""
    weight = np.asarray(geom.frag_weight)
    # T_k = w_k / α_k; a fragment with w = 0 (behind an opaque one, or α·T underflowing)
    # carries nothing and is dropped as well.
    alpha = np.asarray(geom.frag_alpha)
    keep = np.flatnonzero(weight >= FIT_TRANSMITTANCE_CUTOFF * alpha)
    return eqx.tree_at(lambda g: (g.frag_pixel, g.frag_i0, g.frag_t, g.frag_weight, g.frag_alpha),
                       geom, tuple(jnp.asarray(np.asarray(x)[keep]) for x in (
                           geom.frag_pixel, geom.frag_i0, geom.frag_t, geom.frag_weight,
                           geom.frag_alpha)))


def _prepare_terms(scene: Scene, params: ShadingParams, names, target, sqrt_weight) -> _Terms:
    full = geometry_stage(scene)
    geom = _visible_fragments(full)
    lookup = None
    if geom.model in LOOKUP_MODELS:  # §14: the same terms, read from the table
        lookup = lookup_coordinates(geom.tangent, geom.to_light, geom.to_eye)
        sin_tl, _ = lookup_terms(params.shininess, *lookup, geom.lookup_size, geom.model)
        gap = jnp.zeros_like(sin_tl)
    else:
        sin_tl, gap = jax.vmap(kajiya_kay_terms, in_axes=(0, 0, 0, None))(
            geom.tangent, geom.to_light, geom.to_eye, geom.model)
    # §16: the streak factor scales a point's whole colour, so it rides on the light (and
    # the ambient term): [P, 3] instead of [1, 3] with streaks.
    streak = 1.0 if geom.streak is None else geom.streak[:, None]
    light = geom.light_rgb[None, :] * streak
    lit_color = light * geom.base_color
    omega = geom.omega
    tau = None if omega is None else jnp.exp(-params.kappa * omega)
    # The fixed part of the image is computed once, with every fragment.
    # (The backdrop is 0 where the occluder covers the pixel: `_fixed` adds its colour.)
    constant = (composite(full, params.ambient[None, :] * full.base_color * streak)
                + full.transmittance[:, None] * full.backdrop)
    kd_image = ks_image = None
    if "kappa" not in names or omega is None:
        scale = 1.0 if tau is None else tau[:, None]
        kd_image = composite(geom, scale * sin_tl[:, None] * lit_color)
        if "shininess" not in names:
            ks_image = composite(geom, scale * _specular_of(gap, lookup, geom, params.shininess)[:, None]
                                 * light)
    return _Terms(geom, sin_tl, gap, lit_color, light, omega, constant, params.ambient, kd_image,
                  ks_image, jnp.asarray(target), jnp.asarray(sqrt_weight), lookup, geom.lookup_size,
                  geom.model)


def _specular_of(gap, lookup, where, shininess):
    """max(b, 0)^p per point: the guarded power of the gap (§8), or the lookup table read
    at the points' (u, v) (§14); `where` carries the model and table size."""
    if lookup is None:
        return specular_power(gap, shininess)
    return lookup_terms(shininess, *lookup, where.lookup_size, where.model)[1]


def _fixed(terms: _Terms, kappa):
    """ambient⊙A + T·backdrop + T·(the occluder's colour at κ, `occluder_colors`): the image
    without the K_d and K_s terms."""
    g = terms.geometry
    if g.occluder_pixel is None:
        return terms.constant
    occluder = occluder_colors(g, ShadingParams(ambient=terms.ambient, kappa=kappa))
    return terms.constant.at[g.occluder_pixel].add(g.transmittance[g.occluder_pixel][:, None] * occluder)


def _point_terms(terms: _Terms, shininess, kappa):
    """Per point: the Kd and Ks colours before compositing, and their derivatives in κ and p:
    τ·sin·light·c, τ·b^p·light, ∂/∂κ of both (−Ω times them), ∂/∂p of the second."""
    tau = jnp.ones_like(terms.sin_tl) if terms.omega is None else jnp.exp(-kappa * terms.omega)
    omega = jnp.zeros_like(terms.sin_tl) if terms.omega is None else terms.omega
    if terms.lookup is None:
        spec = specular_power(terms.gap, shininess)
        # d(b^p)/dp through the same guarded power: 0 where b ≤ SPECULAR_BASE_EPS, never NaN.
        dspec = jax.vmap(jax.grad(specular_power, argnums=1), in_axes=(0, None))(terms.gap, shininess)
    else:  # §14: the table entries' derivative in p, interpolated like the entries
        spec, dspec = jax.jvp(lambda p: _specular_of(None, terms.lookup, terms, p), (shininess,),
                              (jnp.ones_like(shininess),))
    kd_col = (tau * terms.sin_tl)[:, None] * terms.lit_color
    ks_col = (tau * spec)[:, None] * terms.light
    dks_dp = (tau * dspec)[:, None] * terms.light
    return kd_col, ks_col, -omega[:, None] * kd_col, -omega[:, None] * ks_col, dks_dp


def _kd_ks_images_plain(terms: _Terms, shininess, kappa):
    """(K_d, K_s) images `[HW, 3]` for this κ and shininess (precomputed ones pass through)."""
    kd_col, ks_col, *_ = _point_terms(terms, shininess, kappa)
    kd_image = terms.kd_image if terms.kd_image is not None else composite(terms.geometry, kd_col)
    ks_image = terms.ks_image if terms.ks_image is not None else composite(terms.geometry, ks_col)
    return kd_image, ks_image


# The same function with the one-pass derivative rule below.
_kd_ks_images = jax.custom_jvp(_kd_ks_images_plain)


@_kd_ks_images.defjvp
def _kd_ks_images_jvp(primals, tangents):
    """The images and their derivatives from one composite pass over all the channels.

    Everything here depends on the primal (κ, p) only; the tangent output is a per-pixel
    linear combination, so a Jacobian (vmap over tangent directions) batches only that,
    not the composites. `terms` is data: its tangent is ignored.
    """
    terms, shininess, kappa = primals
    _, d_shininess, d_kappa = tangents
    cols = _point_terms(terms, shininess, kappa)
    images = composite(terms.geometry, jnp.concatenate(cols, axis=1))
    kd_image, ks_image, dkd_dk, dks_dk, dks_dp = jnp.split(images, 5, axis=1)
    if terms.kd_image is not None:  # κ is not fitted: K_d is fixed
        kd_image, dkd_dk = terms.kd_image, jnp.zeros_like(dkd_dk)
    if terms.ks_image is not None:
        ks_image, dks_dk, dks_dp = terms.ks_image, jnp.zeros_like(dks_dk), jnp.zeros_like(dks_dp)
    d_kd = dkd_dk * d_kappa
    d_ks = dks_dk * d_kappa + dks_dp * d_shininess
    return (kd_image, ks_image), (d_kd, d_ks)


def _image(terms: _Terms, kd, ks, shininess, kappa, images=_kd_ks_images):
    """The RGB image [HW, 3] of one target for the given parameter values.
    (`images=_kd_ks_images_plain` gives plain autodiff, which the tests compare against.)"""
    kd_image, ks_image = images(terms, shininess, kappa)
    return _fixed(terms, kappa) + kd[None, :] * kd_image + ks[None, :] * ks_image


# Kd and Ks enter the image linearly (module docstring): with `separable`, `fit` solves
# whichever of them are fitted by non-negative linear least squares at every step
# (variable projection, Golub & Pereyra 1973) and the solver iterates on p and κ only.
_LINEAR = ("kd", "ks")


def _design(terms: _Terms, linear, scalar, params: ShadingParams, shininess, kappa):
    """One target's least-squares problem in the linear unknowns: Φ `[HW·3, n]` (a column
    per fitted Kd/Ks channel, or one for a grey value) and the right-hand side `[HW·3]`,
    both weighted, so that the residuals are Φc − rhs."""
    kd_image, ks_image = _kd_ks_images(terms, shininess, kappa)
    fixed = _fixed(terms, kappa)
    columns = []
    for name, image in (("kd", kd_image), ("ks", ks_image)):
        if name not in linear:
            fixed = fixed + getattr(params, name)[None, :] * image
        elif name in scalar:
            columns.append(image)
        else:
            columns.extend(image * jnp.eye(3, dtype=image.dtype)[None, c] for c in range(3))
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
    arrays = [_target_arrays(s, t, m, w) for s, t, m, w in zip(scenes, target_list, mask_list, weight_list)]
    if scheuermann:
        from ._scheuermann import fit_scheuermann

        return fit_scheuermann(scenes, arrays, names, init, opt, least_squares, scalar, max_steps,
                               rtol, atol, progress)

    start = time.perf_counter()
    terms = [_prepare_terms(s, init, names, t, sw) for s, (t, sw) in zip(scenes, arrays)]
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
    r = [t.sqrt_weight * (_image(t, p.kd, p.ks, p.shininess, p.kappa) - t.target) for t in terms]
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
