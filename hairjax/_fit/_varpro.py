"""Variable projection (Golub & Pereyra 1973; docs/fitting.md, "Variable projection"):
where the image is linear in some fitted gains (`FitModel.linear`), `fit` solves for them by
non-negative least squares at every step and the solver iterates on the rest only."""

from __future__ import annotations

import jax
import jax.numpy as jnp

from ._nnls import nnls
from ._space import value, with_values

__all__ = ["design", "unpack_linear", "project"]


def design(data, fixed, images, params, linear, scalar):
    """One target's least-squares problem in the linear unknowns: Φ `[HW·3, n]` (a column
    per fitted gain channel, or one for a grey value) and the right-hand side `[HW·3]`,
    both weighted, so that the residuals are Φc − rhs. `fixed`, `images`: the model's
    `gain_images` at `params` (a gain not in `linear` enters `fixed` at its value there)."""
    columns = []
    for name, image in images:
        if name not in linear:
            fixed = fixed + value(params, name)[None, :] * image
        elif name in scalar:
            columns.append(image)
        else:
            columns.extend(image * jnp.eye(3, dtype=image.dtype)[None, c] for c in range(3))
    sw = data.sqrt_weight
    phi = jnp.stack([(sw * c).ravel() for c in columns], axis=1)
    return phi, (sw * (data.target - fixed)).ravel()


def unpack_linear(c: jax.Array, linear, scalar) -> dict:
    """The coefficient vector of `design`'s columns as RGB gain values."""
    out, i = {}, 0
    for name in linear:
        k = 1 if name in scalar else 3
        out[name] = jnp.broadcast_to(c[i : i + k], (3,))
        i += k
    return out


def project(model, data, params, linear, scalar):
    """(`params` with the gains in `linear` solved for over all targets, the weighted
    residuals there, flat)."""
    systems = [design(d, *model.gain_images(d, params), params, linear, scalar) for d in data]
    phi = jnp.concatenate([a for a, _ in systems])
    rhs = jnp.concatenate([b for _, b in systems])
    c = nnls(phi, rhs)
    return with_values(params, unpack_linear(c, linear, scalar), model.colours), phi @ c - rhs
