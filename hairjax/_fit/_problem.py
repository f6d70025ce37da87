"""The problem a fit solves (docs/fitting.md, "The problem"): the targets and their
weights, and `Problem`, everything a step needs besides the
solver's z, with the weighted residuals at z."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._scene._scene import Scene
from ._lit import LIGHT_NAMES
from ._model import FitModel
from ._result import FitError
from ._space import from_flat
from ._varpro import project

__all__ = [
    "check_names",
    "target_arrays",
    "Problem",
    "residuals_at",
    "point",
    "jit_point",
    "residuals",
    "residual_fn",
    "loss_fn",
    "params_loss",
]


def check_names(names, scalar, model: FitModel) -> tuple[str, ...]:
    """`names` as a tuple, checked against the model's parameters; `scalar` among its
    colours."""
    names = tuple(names)
    for n in (*names, *scalar):
        if n not in model.fittable:
            also = [x for x in LIGHT_NAMES if x not in model.fittable]
            raise FitError(
                f"unknown parameter {n!r} for a {model.label} scene; fittable: "
                + ", ".join((*model.fittable, *also))
            )
    if len(set(names)) != len(names) or not names:
        raise FitError(f"fit needs distinct parameter names, got {names!r}")
    for n in scalar:
        if n not in model.colours:
            raise FitError(f"only {', '.join(model.colours)} can be fitted as one grey value, not {n!r}")
    return names


def target_arrays(scene: Scene, target, mask, weight):
    """(target `[HW, 3]`, √weight `[HW, 1]`) of one target, its alpha dropped and its mask
    folded into the weights; FitError for a wrong size, NaN pixels or bad weights."""
    h, w = scene.camera.height, scene.camera.width
    image = np.asarray(target, dtype=np.float64)
    if image.ndim != 3 or image.shape[2] < 3:
        raise FitError(f"target for {scene.name!r} must be [H, W, 3 or 4], got {image.shape}")
    if image.shape[:2] != (h, w):
        raise FitError(
            f"target is {image.shape[1]}x{image.shape[0]} but scene {scene.name!r} renders {w}x{h}"
        )
    if not np.all(np.isfinite(image[..., :3])):
        raise FitError(f"target for {scene.name!r} has NaN or infinite pixels")
    wt = np.ones((h, w)) if weight is None else np.broadcast_to(np.asarray(weight, float), (h, w))
    if mask is not None:
        wt = wt * (np.broadcast_to(np.asarray(mask), (h, w)) > 0)
    if not np.all(np.isfinite(wt)) or np.any(wt < 0):
        raise FitError("weights must be finite and non-negative")
    return image[..., :3].reshape(-1, 3), np.sqrt(wt).reshape(-1, 1)


class Problem(eqx.Module):
    """Everything a solver step needs besides z: the targets' data (`FitModel.prepare`'s)
    and the held values (arrays); the model, which names the solver searches and which
    gains are solved for (static). The functions below are module-level and take it as
    `args`, so a compiled step is reused by every fit with the same shapes and names."""

    data: list
    init: object
    model: FitModel = eqx.field(static=True)
    solved: tuple[str, ...] = eqx.field(static=True)
    linear: tuple[str, ...] = eqx.field(static=True)
    scalar: tuple[str, ...] = eqx.field(static=True)


def residuals_at(model: FitModel, params, data) -> jax.Array:
    """The weighted residuals of all targets at `params`, flat."""
    r = [d.sqrt_weight * (model.image(d, params) - d.target) for d in data]
    return jnp.concatenate([x.ravel() for x in r])


def point(z, problem: Problem):
    """The parameters at the solver's z (the gains in `problem.linear` solved for) and the
    residuals there, flat."""
    model = problem.model
    p = from_flat(z, problem.init, problem.solved, model.colours, problem.scalar, model.transforms)
    if not problem.linear:
        return p, residuals_at(model, p, problem.data)
    return project(model, problem.data, p, problem.linear, problem.scalar)


jit_point = eqx.filter_jit(point)


def residuals(z, problem: Problem):
    """The weighted residuals at the solver's z, flat."""
    return point(z, problem)[1]


def _loss(z, problem: Problem):
    return 0.5 * jnp.sum(residuals(z, problem) ** 2)


def residual_fn(z, problem: Problem):
    """optimistix's least-squares `fn`: (residuals, aux)."""
    return point(z, problem)[1], None


def loss_fn(z, problem: Problem):
    """optimistix's minimiser `fn` (BFGS): (½‖r‖², aux)."""
    return _loss(z, problem), None


@eqx.filter_jit
def params_loss(params, model: FitModel, data):
    """½‖r‖² at `params` themselves (no gain solved for), compiled."""
    return 0.5 * jnp.sum(residuals_at(model, params, data) ** 2)
