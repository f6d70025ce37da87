"""Host arrays the CPU device can share instead of copy.

On the CPU backend `jax.device_put` aliases a NumPy array whose data are 64-byte aligned
(XLA's minimum buffer alignment) instead of copying it; NumPy itself aligns only to 16
bytes. The set-up's per-fragment arrays (tens of millions of entries at 100k strands /
1024²) are written into aligned buffers, so that the geometry stage hands them to JAX
without a second copy (BENCHMARKS.md, "Memory"). On another backend the transfer copies
as before.

The set-up's transients (the raster's per-chunk parts, the sort's permutation) are
allocated and freed by the C heap, which keeps what is freed for reuse: after a render at
100k strands / 1024², 1.5 GiB of the process's resident memory was free heap.
`release_heap` hands it back to the system.
"""

from __future__ import annotations

import concurrent.futures
import ctypes
import functools
import gc
import os

import jax
import numpy as np

__all__ = [
    "aligned_empty",
    "available_memory",
    "compile_loop",
    "host_threads",
    "in_parallel",
    "release_heap",
    "release_shared",
    "split_evenly",
    "to_device",
]

ALIGNMENT = 64  # bytes: XLA's CPU buffer alignment


def aligned_empty(n: int, dtype) -> np.ndarray:
    """An uninitialised `[n]` array of `dtype` whose data start on an ALIGNMENT boundary."""
    dtype = np.dtype(dtype)
    raw = np.empty(n * dtype.itemsize + ALIGNMENT, np.uint8)
    offset = -raw.ctypes.data % ALIGNMENT
    return raw[offset : offset + n * dtype.itemsize].view(dtype)


def to_device(x: np.ndarray | jax.Array, dtype) -> jax.Array:
    """`x` as a JAX array of `dtype`: shared, not copied, when `x` is aligned and of that
    dtype on the CPU backend (`aligned_empty`); `x` is then made read-only. A JAX array
    (the set-up's on a device, `_device_raster`) stays where it is."""
    if isinstance(x, jax.Array):
        return x.astype(dtype)
    x = np.asarray(x)
    if x.dtype != np.dtype(dtype):
        x = x.astype(dtype)
    else:
        # Possibly shared from here on (any 64-byte aligned array is): a later write
        # through NumPy would change the JAX array too.
        x.flags.writeable = False
    return jax.device_put(x)


def release_shared() -> None:
    """Let XLA drop the NumPy arrays it shared with arrays that are gone (`to_device`).

    XLA hands those references back to Python only when the garbage collector runs
    (JAX's `_xla_gc_callback` on `gc.callbacks`, in `jax/_src/lib/__init__.py`), and the
    set-up's loops create almost no Python objects, so none runs while they allocate: a
    previous render's fragment arrays (0.66 GB at 100k strands / 1024²) stayed resident
    through the next set-up. A collection of the youngest generation runs the callback, in
    well under a millisecond."""
    gc.collect(0)


def _malloc_trim():
    """glibc's `malloc_trim`, or None where the C library has none."""
    try:
        return ctypes.CDLL(None).malloc_trim
    except (OSError, AttributeError, TypeError):  # fires off glibc: macOS, musl, Windows
        return None


_MALLOC_TRIM = _malloc_trim()


# Below this, what the C heap keeps is small against the process, and a trim (with the
# pages faulted in again when the heap is reused) costs more than it returns: 55 ms of a
# 1.3 s render at 20k strands / 512² (5.5 M fragments, about 110 MB of them).
RELEASE_MIN_BYTES = 256 << 20


def release_heap(freed: int) -> None:
    """Return the C heap's free memory to the system (glibc's `malloc_trim(0)`, which also
    releases free pages inside the heap) after transients of about `freed` bytes were
    released, when that is at least RELEASE_MIN_BYTES; nothing where the C library has no
    such call."""
    if _MALLOC_TRIM is not None and freed >= RELEASE_MIN_BYTES:
        _MALLOC_TRIM(0)


def host_threads() -> int:
    """The CPU cores this process may run on (its affinity mask, where the OS has one)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # fires off Linux: no affinity mask
        return max(1, os.cpu_count() or 1)


@functools.cache
def _pool() -> concurrent.futures.ThreadPoolExecutor:
    return concurrent.futures.ThreadPoolExecutor(host_threads(), thread_name_prefix="hairjax-set-up")


def in_parallel(tasks: list) -> list:
    """`[task() for task in tasks]`, the tasks run at once on the set-up's threads: for the
    compiled loops (`nogil`), which so run on every core. A single task runs here."""
    if len(tasks) == 1:
        return [tasks[0]()]
    return list(_pool().map(lambda task: task(), tasks))


def split_evenly(weights: np.ndarray, parts: int) -> list[int]:
    """Bounds `[0, b₁, …, n]` of at most `parts` contiguous runs of `weights` (`[n]`,
    non-negative) with about equal sums; fewer runs where there are fewer items, and one
    (empty) run `[0, 0]` for no items."""
    cum = np.cumsum(weights)
    if cum.size == 0:
        return [0, 0]
    inner = np.searchsorted(cum, cum[-1] * np.arange(1, parts) / parts, side="left") + 1
    return sorted({0, cum.size, *(min(int(b), cum.size) for b in inner)})


def available_memory() -> int | None:
    """Bytes of memory available to a new allocation without swapping (Linux's
    MemAvailable), or None where the system does not say."""
    try:
        with open("/proc/meminfo") as meminfo:
            for line in meminfo:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):  # fires off Linux, or on an unexpected format
        return None
    return None


def compile_loop(**options):
    """A decorator: `numba.njit(nogil=True, **options)`, the machine code cached on disk
    (beside the package, or in the user's cache folder when the package's is read-only),
    or compiled afresh in each process where neither folder is writable (numba then
    refuses to cache at all). numba is imported on first use: the GL renderer and the
    command line's start-up do not load it."""

    def compile(fn):
        import numba

        try:
            return numba.njit(cache=True, nogil=True, **options)(fn)
        except RuntimeError:  # fires where no cache folder is writable ("no locator available")
            return numba.njit(nogil=True, **options)(fn)

    return compile
