"""Several targets as one batch (docs/fitting.md, "Several views and lights"): the
targets' terms stacked on a leading axis and the model's image taken under `vmap`, so a
fit of V views or lights compiles its step once, not V times.

The targets' geometries are padded to the longest (`pad_geometries`: a padded fragment
has weight 0 and pixel H·W, which the composite's scatters drop), and the rest of their
terms stack as they are where they have one structure and shape (the same image size and
hair, the same fitted names reaching the same gains). Where they do not, the targets stay
a list and the model runs once per target, as before.
"""

from __future__ import annotations

import dataclasses
import functools
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp

from .._views import pad_geometries
from ._model import FitModel
from ._shading_fit import TargetTerms

__all__ = ["BatchedTerms", "batched", "batched_model"]


class BatchedTerms(eqx.Module):
    """V targets' terms stacked (`terms`, leading axis V); their targets and √weights
    flat, `[V·HW, 3]` and `[V·HW, 1]`, as the model's batched image is."""

    terms: Any
    target: jax.Array
    sqrt_weight: jax.Array


def _same_leaves(trees) -> bool:
    structure: Any = jax.tree.structure(trees[0])  # PyTreeDef's stubs declare no __eq__
    shapes = [jnp.shape(x) for x in jax.tree.leaves(trees[0])]
    return all(
        structure == jax.tree.structure(t) and [jnp.shape(x) for x in jax.tree.leaves(t)] == shapes
        for t in trees[1:]
    )


def batched(data: list) -> list:
    """`[BatchedTerms]` of the targets' terms where they stack, else `data` as it is."""
    if len(data) < 2 or not all(isinstance(d, TargetTerms) for d in data):
        return data
    geometries = [d.geometry for d in data]
    if len({g.occluder_pixel is None for g in geometries}) > 1:
        return data
    # Padded to the longest exactly: a fit compiles per fit's shapes anyway.
    padded = [
        dataclasses.replace(d, geometry=g)
        for d, g in zip(data, pad_geometries(geometries, round_up=lambda n: max(int(n), 1)))
    ]
    if not _same_leaves(padded):
        return data
    stacked = jax.tree.map(lambda *xs: jnp.stack(xs), *padded)
    return [
        BatchedTerms(
            stacked,
            jnp.concatenate([d.target for d in data]),
            jnp.concatenate([d.sqrt_weight for d in data]),
        )
    ]


@functools.cache
def batched_model(model: FitModel) -> FitModel:
    """`model` on `BatchedTerms`: its image and gain images under `vmap` over the
    targets, flattened to `[V·HW, 3]` (one per class of model, as the models are)."""

    def image(b: BatchedTerms, params):
        return jax.vmap(lambda t: model.image(t, params))(b.terms).reshape(-1, 3)

    def gain_images(b: BatchedTerms, params):
        order: list[str] = []

        def one(t):
            fixed, images = model.gain_images(t, params)
            order[:] = [n for n, _ in images]  # the names, read while tracing
            return fixed, dict(images)

        fixed, images = jax.vmap(one)(b.terms)
        return fixed.reshape(-1, 3), tuple((n, images[n].reshape(-1, 3)) for n in order)

    return dataclasses.replace(
        model, image=image, gain_images=None if model.gain_images is None else gain_images
    )
