"""The set-up's aligned fragment arrays are shared with JAX, not copied (hairjax/_geometry/_host.py)."""

import sys

import jax
import numpy as np
import pytest
from helpers import small_furball_scene

from hairjax._geometry._host import (
    _MALLOC_TRIM,
    ALIGNMENT,
    RELEASE_MIN_BYTES,
    aligned_empty,
    release_heap,
    to_device,
)
from hairjax._geometry._placement import PLACEMENT_VARIABLE
from hairjax._geometry_stage._setup import prepare
from hairjax._geometry_stage._stage import geometry_stage

cpu_only = pytest.mark.skipif(jax.default_backend() != "cpu", reason="the CPU backend aliases host arrays")


@pytest.fixture
def host_setup(monkeypatch):
    """The set-up's loops on the host, whatever HAIRJAX_SETUP says: what shares buffers."""
    monkeypatch.setenv(PLACEMENT_VARIABLE, "host")


@pytest.mark.parametrize("n", [1, 7, 1000])  # (an empty array has no data to align)
@pytest.mark.parametrize("dtype", [np.int32, np.float32, np.float64, np.bool_])
def test_aligned_empty_is_aligned(n, dtype):
    x = aligned_empty(n, dtype)
    assert x.shape == (n,) and x.dtype == dtype and x.ctypes.data % ALIGNMENT == 0


@cpu_only
def test_to_device_shares_an_aligned_array_and_copies_otherwise():
    x = aligned_empty(4096, np.int32)
    x[:] = np.arange(4096)
    shared = to_device(x, np.int32)
    assert shared.unsafe_buffer_pointer() == x.ctypes.data
    cast = to_device(x, np.float32)  # another dtype: converted, a new buffer
    assert cast.unsafe_buffer_pointer() != x.ctypes.data
    np.testing.assert_array_equal(np.asarray(cast), x)


@cpu_only
def test_the_geometry_stage_shares_the_set_ups_fragments(host_setup):
    """frag_pixel and frag_i0 (int32 in both) are the set-up's own buffers: the geometry
    stage adds no copy of them (BENCHMARKS.md, "Memory")."""
    scene = small_furball_scene(strands=100, size=32)
    setup, geometry = prepare(scene), geometry_stage(scene, cutoff=0.0)
    assert setup.frag_pixel.size > 0
    assert geometry.frag_pixel.unsafe_buffer_pointer() == setup.frag_pixel.ctypes.data
    assert geometry.frag_i0.unsafe_buffer_pointer() == setup.frag_i0.ctypes.data


def _resident_bytes() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096


@pytest.mark.skipif(_MALLOC_TRIM is None or not sys.platform.startswith("linux"), reason="glibc only")
def test_release_heap_returns_freed_heap_to_the_system():
    """Blocks of 256 KiB come from the C heap once glibc has raised its mmap threshold
    (the first freed mapping raises it). 200 of them are freed behind one that stays
    allocated, so the heap cannot shrink from its top: their 50 MiB stay resident until
    `release_heap` is told of a large enough transient, and must then return at least half
    of them."""
    block = 256 * 1024
    np.ones(2 * block, np.uint8)  # mapped, then freed: raises the threshold above `block`
    held = [np.ones(block, np.uint8) for _ in range(200)]
    pin = np.ones(block, np.uint8)
    del held
    before = _resident_bytes()
    release_heap(0)  # below RELEASE_MIN_BYTES: kept
    assert before - _resident_bytes() < 20 * block
    release_heap(RELEASE_MIN_BYTES)
    assert before - _resident_bytes() >= 100 * block
    del pin


def test_in_parallel_returns_results_in_task_order():
    import functools
    import threading

    from hairjax._geometry._host import host_threads, in_parallel

    assert host_threads() >= 1
    tasks = [functools.partial(lambda i: (i * i, threading.get_ident()), i) for i in range(5)]
    results = in_parallel(tasks)
    assert [r[0] for r in results] == [0, 1, 4, 9, 16]
    # A single task runs in the calling thread (no hand-off for the small scenes).
    assert in_parallel(tasks[:1])[0][1] == threading.get_ident()


@cpu_only
def test_release_shared_lets_xla_drop_a_forgotten_scenes_fragments(host_setup):
    import gc
    import weakref

    from hairjax._cache import forget
    from hairjax._geometry._host import release_shared

    scene = small_furball_scene()
    geometry_stage(scene)  # shares the set-up's fragment arrays with JAX
    base = prepare(scene).frag_pixel
    while base.base is not None:
        base = base.base
    buffer = weakref.ref(base)
    del base
    enabled = gc.isenabled()
    gc.disable()  # no collection by chance: only release_shared's
    try:
        forget(scene)
        release_shared()
        assert buffer() is None
    finally:
        if enabled:
            gc.enable()


def test_compiled_loops_work_where_no_cache_folder_is_writable(monkeypatch):
    """numba refuses `cache=True` when neither the package's folder nor the user's cache
    folder is writable (a read-only install and home); `compile_loop` then compiles
    without caching, and the raster runs the same."""
    from typing import no_type_check

    from numba.core import caching

    from hairjax._geometry import _raster, _raster_loop
    from hairjax._geometry._host import compile_loop

    p = np.array([[1.0, 2.0], [3.5, 12.0]])
    before = _raster.rasterize(p[:1], p[1:], np.ones(1), np.ones(1), np.full(1, 2.0), 16, 16, False)
    monkeypatch.setattr(caching.CacheImpl, "_locator_classes", [])  # no folder can hold a cache

    @compile_loop()
    @no_type_check
    def add(a, b):
        return a + b

    assert add(2, 3) == 5
    loops = (_raster_loop.raster_loop, _raster_loop.coverage_loop, _raster_loop._depth_loop)
    for loop in loops:  # the raster's loops compiled afresh, under the same condition
        loop.cache_clear()
    try:
        after = _raster.rasterize(p[:1], p[1:], np.ones(1), np.ones(1), np.full(1, 2.0), 16, 16, False)
    finally:
        for loop in loops:
            loop.cache_clear()
    assert after.size > 10
    for name in ("pixel", "segment", "coverage", "t", "depth"):
        np.testing.assert_array_equal(getattr(after, name), getattr(before, name))


def test_split_evenly_by_hand():
    from hairjax._geometry._host import split_evenly

    # Sums 1, 1, 1, 1, 4: halves at a cumulative 4 → [0, 4) and [4, 5).
    assert split_evenly(np.array([1, 1, 1, 1, 4]), 2) == [0, 4, 5]
    assert split_evenly(np.array([2, 2, 2, 2]), 4) == [0, 1, 2, 3, 4]
    assert split_evenly(np.array([5, 0, 0]), 3) == [0, 1, 3]  # empty runs merge away
    assert split_evenly(np.array([3, 3]), 1) == [0, 2]
    assert split_evenly(np.array([], np.int64), 2) == [0, 0]
