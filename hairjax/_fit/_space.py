"""The solver's parameter space (docs/fitting.md, "Parametrisation: where parameters stay
valid and well scaled") and the space of the standard errors.

The solver iterates on an unconstrained flat z; each fitted parameter x is a transform of its
entries: softplus for the colour gains (x ≥ 0), exp for the scale-free exponents and the
extinction κ (x > 0), the identity for the tangent shifts. An RGB parameter takes three
entries, or one when it is fitted as a grey value. The light's direction (`_lit.py`) takes
two, through a transform relative to a reference direction, the base point's own.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import jax
import jax.numpy as jnp

from .._shading._transforms import IDENTITY, LOG, LOGIT, SOFTPLUS, Transform, identity, softplus, softplus_inv
from ._lit import RelativeTransform
from ._point import ExtendedParams

__all__ = [
    "Transform",
    "SOFTPLUS",
    "LOG",
    "IDENTITY",
    "START_FLOOR",
    "value",
    "softplus",
    "softplus_inv",
    "identity",
    "error_space",
    "entries",
    "to_flat",
    "unflatten",
    "from_flat",
    "with_values",
]


# Smallest value a parameter starts from, and the smallest at which a log-space standard
# error is taken: the inverse transforms need x > 0 (fires for a start at 0, e.g. Ks = 0).
START_FLOOR = 1e-6


def error_space(space: Mapping[str, Transform | RelativeTransform]) -> dict:
    """Where the standard errors are taken: the gains and the strands' opacity themselves (0
    is a valid gain, where the softplus z of the solver is not; an opacity's error is one in
    α, not in its logit), every other parameter as the solver sees it (log
    exponents and κ, shifts as they are)."""
    return {n: IDENTITY if t is SOFTPLUS or t is LOGIT else t for n, t in space.items()}


def value(params, name: str):
    """The parameter `name` of `params` (a model's parameters, or `ExtendedParams`)."""
    return params.get(name) if isinstance(params, ExtendedParams) else getattr(params, name)


def entries(name: str, colours, scalar, space: Mapping | None = None) -> int:
    """How many entries of z a parameter takes: 3 for an RGB one, 1 for a grey value or a
    scalar, a `RelativeTransform`'s size (2 for the light's direction) in `space`."""
    transform = None if space is None else space.get(name)
    if isinstance(transform, RelativeTransform):
        return transform.size
    return 3 if name in colours and name not in scalar else 1


def to_flat(params, names, scalar, space: Mapping, reference=None) -> jax.Array:
    """The flat z of `params` in `space` over `names` (a grey value as the mean of its
    channels). Values below START_FLOOR are raised to it first where `space` needs x > 0.
    A `RelativeTransform` is taken about `reference`'s value (default: `params`' own, z = 0)."""
    reference = params if reference is None else reference
    parts = []
    for n in names:
        x = jnp.asarray(value(params, n))
        if isinstance(space[n], RelativeTransform):
            parts.append(space[n].inverse(x, value(reference, n)))
            continue
        if space[n].floored:
            x = jnp.maximum(x, START_FLOOR)
        if n in scalar:
            x = jnp.mean(x, keepdims=True)
        parts.append(jnp.ravel(space[n].inverse(x)))
    return jnp.concatenate(parts) if parts else jnp.zeros(0, dtype=jnp.result_type(float))


def unflatten(z: jax.Array, names, colours, scalar, space: Mapping | None = None) -> dict:
    """{name: its entries of z}, in `names` order (`space`: for the sizes of relative
    transforms)."""
    out, i = {}, 0
    for n in names:
        k = entries(n, colours, scalar, space)
        out[n], i = z[i : i + k], i + k
    return out


def from_flat(z: jax.Array, base, names, colours, scalar, space: Mapping):
    """`base` with the parameters in `names` taken from z through `space` (a
    `RelativeTransform` about `base`'s own value)."""
    values = {}
    for n, v in unflatten(z, names, colours, scalar, space).items():
        t = space[n]
        values[n] = t.forward(v, value(base, n)) if isinstance(t, RelativeTransform) else t.forward(v)
    return with_values(base, values, colours)


def with_values(base, values: dict, colours):
    """`base` (a model's parameters, or `ExtendedParams`, built through their own constructor,
    whose checks pass traced values) with some parameters replaced; a single value of an
    RGB one broadcasts, every other takes the shape of `base`'s."""
    shaped = {
        n: jnp.broadcast_to(x, (3,)) if n in colours else jnp.reshape(x, jnp.shape(value(base, n)))
        for n, x in values.items()
    }
    return base.replace(shaped) if isinstance(base, ExtendedParams) else dataclasses.replace(base, **shaped)
