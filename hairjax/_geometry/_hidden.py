"""Fragments hidden behind their pixel's nearer ones, left out of the composite
(docs/model.md §6).

Front to back, a pixel's k-th fragment is seen through T_k = Π_{j nearer} (1 − α_j) of
the fragments before it. T never grows along the run, so the fragments with T_k below a
cutoff c are the run's tail, and their weights w = α·T add up to T_first − T ≤ c: left
out, they move the pixel by less than c times the brightest colour among them.

- The renderer's cutoff is half the working precision's epsilon (`drawn_cutoff`: 2⁻²⁴ in
  float32, 2⁻⁵³ in float64), below the rounding of a colour of order one. The dense fur
  ball at 100k strands / 1024² then keeps 30 % of its 55 M fragments (a pixel at its
  centre holds up to 10 k; a quarter of all have w = 0 exactly, α·T underflowing), and
  the shading stage reads only those (BENCHMARKS.md, "Where the time goes").
- The fit composites each step with a coarser cut (`FIT_TRANSMITTANCE_CUTOFF`).

Which fragments are hidden depends on the opacities, so the cut is made once they are
known (`keep_visible`), and a traced α (the opacity's gradient) keeps every fragment. On
the CPU the cut runs in NumPy, into buffers JAX shares (`_host`); on another device it
stays there, after one round-trip for the count of kept fragments. The geometry stage
pads what it keeps to its bucket (`fragment_bucket`, docs/model.md §6).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from ._capacity import fragment_bucket
from ._host import aligned_empty, to_device

__all__ = ["drawn_cutoff", "keep_visible", "keep_on_host", "keep_on_device"]


def drawn_cutoff(dtype) -> float:
    """The renderer's cutoff in the floating type `dtype`: half its epsilon (module
    docstring)."""
    return float(np.finfo(dtype).eps) / 2


def keep_visible(visible: jax.Array, *fields: jax.Array, fills=None) -> tuple[jax.Array, ...]:
    """Each of `fields` (`[F]`) at the entries where `visible` (`[F]` bool) is set, in
    order: on the host for arrays on the CPU, else on their device. `fills` (one value per
    field): pad the kept entries to their `fragment_bucket` with these."""
    on_cpu = all(d.platform == "cpu" for d in visible.devices())
    return (keep_on_host if on_cpu else keep_on_device)(visible, *fields, fills=fills)


def keep_on_host(visible, *fields, fills=None) -> tuple[jax.Array, ...]:
    """`keep_visible` through NumPy: 0.15 s for the 55 M fragments of the dense bench fur
    ball, against 0.63 s for XLA's `nonzero` on 2 cores (BENCHMARKS.md)."""
    index = np.flatnonzero(np.asarray(visible))
    size = index.size if fills is None else fragment_bucket(index.size)
    kept = []
    for k, f in enumerate(fields):
        out = aligned_empty(size, f.dtype)
        # mode="clip": with the default "raise", NumPy writes through a temporary buffer when
        # `out` is given; the indices are in range, so clipping never changes one.
        np.take(np.asarray(f), index, out=out[: index.size], mode="clip")
        if fills is not None:
            out[index.size :] = fills[k]
        kept.append(to_device(out, out.dtype))
    return tuple(kept)


def keep_on_device(visible, *fields, fills=None) -> tuple[jax.Array, ...]:
    """`keep_visible` where the arrays live, with one host round-trip for the count."""
    count = int(jnp.count_nonzero(visible))
    size = count if fills is None else fragment_bucket(count)
    index = jnp.nonzero(visible, size=size, fill_value=0)[0]
    kept = (jnp.take(f, index, mode="clip") for f in fields)  # clip: in range, never fires
    if fills is None:
        return tuple(kept)
    real = jnp.arange(size) < count  # the bucket's tail: padding
    return tuple(jnp.where(real, k, v) for k, v in zip(kept, fills))
