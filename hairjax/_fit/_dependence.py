"""Which inputs an output of a JAX function depends on, read off its jaxpr: how the fit
knows which gain images a fitted parameter reaches (docs/fitting.md, "What a step
recomputes"), for any shading model, without the model saying so.

The analysis is structural and conservative: an equation's outputs depend on all of its
inputs (a call, a loop or a custom rule included), so an output is reported independent of
an input only when no path of equations joins them. Then the output is the same function
of the other inputs whatever that input is, and an image built from it can be computed
once.
"""

from __future__ import annotations

from collections.abc import Callable

import jax
from jax.extend.core import Literal

__all__ = ["dependence"]


def dependence(fn: Callable, *args):
    """`fn(*args)`'s output structure with, at each leaf, the set of indices of the leaves
    of `args` that leaf depends on (one trace of `fn`)."""
    closed, shapes = jax.make_jaxpr(fn, return_shape=True)(*args)
    jaxpr = closed.jaxpr
    deps: dict = {}
    for i, v in enumerate(jaxpr.invars):
        deps[v] = {i}
    for v in jaxpr.constvars:
        deps[v] = set()

    def of(atom) -> set[int]:
        # Literals (constants written into an equation) carry no input.
        return set() if isinstance(atom, Literal) else deps.get(atom, set())

    for eqn in jaxpr.eqns:
        inputs = set().union(*(of(a) for a in eqn.invars)) if eqn.invars else set()
        for v in eqn.outvars:
            deps[v] = inputs
    return jax.tree.unflatten(jax.tree.structure(shapes), [of(v) for v in jaxpr.outvars])
