"""The transforms a fit searches a model's non-linear parameters through (docs/fitting.md).

Each is `(forward, inverse)` from the solver's unconstrained z to the parameter x: the
models name them in `AbstractShadingModel.searched`, and `hairjax/_fit/` applies them.
"""

from __future__ import annotations

import jax.numpy as jnp

__all__ = ["LOG", "SOFTPLUS", "IDENTITY", "softplus", "softplus_inverse"]


def softplus(z):
    return jnp.logaddexp(z, 0.0)


def softplus_inverse(x):
    # log(expm1(x)), written to stay accurate for small and large x.
    return x + jnp.log(-jnp.expm1(-x))


def _identity(x):
    return x


# Scale-free positive parameters (an exponent, an extinction): x = exp(z).
LOG = (jnp.exp, jnp.log)
# Non-negative gains searched by the solver itself (not solved for): x = softplus(z).
SOFTPLUS = (softplus, softplus_inverse)
# Signed parameters (a tangent shift): x = z.
IDENTITY = (_identity, _identity)
