"""The camera's fragments that can be seen, found before they are grouped by pixel
(docs/model.md §6, "Hidden fragments").

A pixel's fragments are composited front to back through T_k = Π_{j nearer} (1 − α_j),
which only falls along the pixel's run; once it is below a cutoff c, every later fragment
of the pixel adds less than c times its colour in all (`_hidden`). The draw order is known
before the raster (bins, static and none orderings: the camera raster runs nearest
segment first), so the raster itself tracks each pixel's T, in float64, and writes no
fragment seen through less than c (`raster_loop`'s `seen`): those are never grouped,
weighed nor shaded.

- *The host* (`rasterize_seen`) rasterises in pieces of consecutive segments, one per
  core, at once. The first piece starts at T = 1 everywhere and its cut is exact. Each
  later piece starts at T = 1 too and cuts by its own fragments alone: that T is at least
  the pixel's true one, so it only leaves out fragments the exact cut leaves out. A pass
  over the later pieces in draw order (`carry_on`) then carries the true T on and cuts
  what is left.
- *The device* (`seen_on_device`) cannot run one loop in draw order. It walks the
  candidates in draw order, SEEN_CHUNK at a time, and drops a fragment when its pixel's
  T before the chunk is below c: a bound in the same spirit, as T before a fragment is at
  most T before its chunk. It keeps the fragments a chunk hides within itself.

Which fragments are hidden depends on the opacities, so a set-up cut this way is one of
concrete per-strand α (`prepare(..., cutoff=...)`); a traced α keeps every fragment. The
cut here is a bound of the exact cut the geometry stage makes on the composite's own
weights (`keep_visible`): it is made at `SETUP_MARGIN` times the stage's cutoff, so that
float rounding, T here in float64 against the composite's product scan in the working
precision, never leaves out a fragment the exact cut keeps (that would take a relative
rounding error of ½ in T).
"""

from __future__ import annotations

import functools
from typing import NamedTuple, no_type_check

import jax
import jax.numpy as jnp
import numpy as np

from ._host import compile_loop
from ._raster import Fragments, rasterize_parts
from ._raster_loop import seen_through_loop
from ._raster_plan import RibbonRaster

__all__ = ["Seen", "SeenPieces", "SETUP_MARGIN", "SEEN_CHUNK", "rasterize_seen", "seen_on_device"]

# The set-up cuts at this times the geometry stage's cutoff (module docstring).
SETUP_MARGIN = 0.5

# Candidates per step of the device's walk in draw order: 2^20 walk the 200 M candidates
# of 100k strands at 1024² in 200 steps.
SEEN_CHUNK = 1 << 20


class Seen(NamedTuple):
    """What the raster's test of each fragment reads: the occluder's depth at every pixel
    centre (`hit`, `[H·W]`; None: no occluder) and, to cut hidden fragments, each label's
    segment opacity (`opacity`, `[labels]` float64: the strand's α times the segment's
    alpha texture; None: no cut) and the `cutoff`."""

    hit: np.ndarray | None
    opacity: np.ndarray | None
    cutoff: float


class SeenPieces(NamedTuple):
    """`rasterize_seen`'s result: the raster's `pieces` (`Fragments`, in draw order) and,
    where hidden fragments were cut, each pixel's product of their (1 − α)
    (`hidden`, `[H·W]` float64; None without a cut), which its transmittance keeps."""

    pieces: list[Fragments]
    hidden: np.ndarray | None


def rasterize_seen(
    raster: RibbonRaster, labels: np.ndarray, seen: Seen, *, parts: int | None = None
) -> SeenPieces:
    """`rasterize_parts`' pieces of `raster` (no depth; `parts` of them, by default one
    per core), each fragment naming its entry of `labels`, without those behind the
    occluder or hidden (module docstring)."""
    empty = np.empty(0)
    hit = empty if seen.hit is None else np.ascontiguousarray(seen.hit, np.float64)
    opacity = empty if seen.opacity is None else np.ascontiguousarray(seen.opacity, np.float64)
    cutoff = float(seen.cutoff)
    cut = seen.opacity is not None
    hidden = np.ones(raster.pixels) if cut else empty  # the pieces multiply it in turn, never at once
    transmittance: dict[int, np.ndarray] = {}
    hidden_of: dict[int, np.ndarray] = {}

    def test(k: int) -> tuple:
        transmittance[k] = np.ones(raster.pixels) if cut else empty
        hidden_of[k] = (np.ones(raster.pixels) if k else hidden) if cut else empty
        return (hit, opacity, transmittance[k], hidden_of[k], cutoff)

    pieces = rasterize_parts(**raster._asdict(), depth=False, labels=labels, parts=parts, seen=test)
    if not cut:
        return SeenPieces(pieces, None)
    carry = _carry_loop()
    running = transmittance[0]
    kept = [pieces[0]]
    for k, piece in enumerate(pieces[1:], start=1):
        hidden *= hidden_of[k]
        count = carry(piece.pixel, piece.segment, piece.coverage, piece.t, opacity, running, hidden, cutoff)
        kept.append(piece.take(slice(0, count)))
    return SeenPieces(kept, hidden)


@functools.cache
def _carry_loop():
    """`carry_on` compiled by numba (on first use; cached on disk, `compile_loop`)."""
    seen_through = seen_through_loop()

    @compile_loop(error_model="numpy")
    @no_type_check
    def carry_on(pixel, segment, coverage, t, opacity, transmittance, hidden, cutoff):
        """The fragments of a later piece (in draw order, already cut by their own T) seen
        through at least `cutoff` of the `transmittance` the pieces before leave, moved to
        the front in order; their number. `transmittance` is carried on, and the (1 − α)
        of those it cuts multiply `hidden`, in place."""
        kept = 0
        for k in range(pixel.size):
            p = pixel[k]
            if not seen_through(opacity[segment[k]] * coverage[k], p, transmittance, hidden, cutoff):
                continue
            pixel[kept], segment[kept], coverage[kept], t[kept] = p, segment[k], coverage[k], t[k]
            kept += 1
        return kept

    return carry_on


def seen_on_device(
    pixel: jax.Array,
    keep: jax.Array,
    segment: jax.Array,
    coverage: jax.Array,
    opacity,
    cutoff: float,
    n_pixels: int,
    *,
    chunk: int = SEEN_CHUNK,
) -> tuple[jax.Array, jax.Array]:
    """`keep` (`[C]` bool, candidates in draw order) without the candidates whose pixel's
    T before their `chunk` of candidates is below `cutoff` (module docstring), and each
    pixel's product of the (1 − α) of those left out (`[H·W]`); `opacity` (`[labels]`)
    is each label's segment opacity."""
    opacity = jnp.asarray(opacity, coverage.dtype)
    return _seen_chunks(pixel, keep, segment, coverage, opacity, cutoff, n_pixels, chunk)


@functools.partial(jax.jit, static_argnums=(6, 7))
def _seen_chunks(pixel, keep, segment, coverage, opacity, cutoff, n_pixels, chunk):
    n = pixel.shape[0]
    steps = -(-n // chunk)
    pad = steps * chunk - n
    # The padding is not kept, so it neither passes nor dims a pixel.
    p, k, s, c = (jnp.pad(x, (0, pad)) for x in (pixel, keep, segment, coverage))
    p = jnp.where(k, p, n_pixels)  # the candidates not kept dim no pixel: scattered past the end

    def step(state, chunk):
        transmittance, hidden = state
        cp, ck, cs, cc = chunk
        seen = ck & (transmittance[jnp.minimum(cp, n_pixels - 1)] >= cutoff)
        through = jnp.where(ck, 1.0 - opacity[cs] * cc, 1.0)
        transmittance = transmittance.at[cp].multiply(jnp.where(seen, through, 1.0), mode="drop")
        hidden = hidden.at[cp].multiply(jnp.where(seen, 1.0, through), mode="drop")
        return (transmittance, hidden), seen

    chunks = tuple(x.reshape(steps, chunk) for x in (p, k, s, c))
    ones = jnp.ones(n_pixels, coverage.dtype)
    (_, hidden), seen = jax.lax.scan(step, (ones, ones), chunks)
    return seen.reshape(-1)[:n], hidden
