"""The transforms a fit searches a model's parameters through (docs/fitting.md,
"Parametrisation"): `(forward, inverse, floored)` from the solver's unconstrained z to the
parameter x. The shading models name one per searched parameter
(`AbstractShadingModel.searched`); `hairjax/_fit/` applies them, and SOFTPLUS to a gain the
solver searches itself (`separable=False`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import jax.numpy as jnp

__all__ = ["Transform", "LOG", "SOFTPLUS", "IDENTITY", "LOGIT", "softplus", "softplus_inv", "identity"]


def softplus(z):
    return jnp.logaddexp(z, 0.0)


def softplus_inv(x):
    # log(expm1(x)), written to stay accurate for small and large x.
    return x + jnp.log(-jnp.expm1(-x))


def identity(x):
    return x


class Transform(NamedTuple):
    """z → x (`forward`) and x → z (`inverse`); `floored`: the inverse needs x > 0, and
    values below the fit's START_FLOOR are raised to it before it is applied."""

    forward: Callable
    inverse: Callable
    floored: bool


# Scale-free positive parameters (an exponent, an extinction): x = exp(z).
LOG = Transform(jnp.exp, jnp.log, floored=True)
# Non-negative gains searched by the solver itself (not solved for): x = softplus(z).
SOFTPLUS = Transform(softplus, softplus_inv, floored=True)
# Signed parameters (a tangent shift): x = z.
IDENTITY = Transform(identity, identity, floored=False)


# Clamp for the logit's argument: x in (0, 1) is needed, and a start at 0 or 1 (an opaque
# strand, α = 1) would give z = ±∞. Fires only for such a start.
_OPEN_UNIT = 1e-6


def _logit(x):
    x = jnp.clip(x, _OPEN_UNIT, 1.0 - _OPEN_UNIT)
    return jnp.log(x) - jnp.log1p(-x)


def _sigmoid(z):
    return 0.5 * (1.0 + jnp.tanh(0.5 * z))  # = 1 / (1 + e^−z), without overflow for z ≪ 0


# Opacities in (0, 1) (the strands' α, fitted): x = sigmoid(z).
LOGIT = Transform(_sigmoid, _logit, floored=False)
