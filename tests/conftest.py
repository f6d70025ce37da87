"""Strict test settings (as optimistix's): float64 on, rank promotion raises."""

import atexit
import os
import shutil
import tempfile

# One on-disk XLA cache for the whole test run, in a fresh temporary folder (never the home
# folder), removed when the run ends. The process that loads this first (pytest, or
# pytest-xdist's controller) makes it; xdist's workers, the notebooks' kernels and any
# subprocess inherit the variables, so a kernel compiled by one of them (the module
# fixtures' fits on both workers, a fit after jax.clear_caches(), ...) is loaded, not
# compiled again, by the others. The cache is keyed by the compiled program, so what a test
# computes does not change. JAX reads the JAX_* variables when it is imported.
if "HAIRJAX_TEST_XLA_CACHE" not in os.environ:
    _cache = tempfile.mkdtemp(prefix="hairjax-test-xla-")
    os.environ["HAIRJAX_TEST_XLA_CACHE"] = _cache
    os.environ["JAX_COMPILATION_CACHE_DIR"] = _cache
    os.environ["JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS"] = "0"
    atexit.register(shutil.rmtree, _cache, ignore_errors=True)

import jax  # noqa: E402

# Also set here, in case a plugin imported JAX before this file ran.
jax.config.update("jax_compilation_cache_dir", os.environ["HAIRJAX_TEST_XLA_CACHE"])
jax.config.update("jax_persistent_cache_min_compile_time_secs", 0)
jax.config.update("jax_enable_x64", True)
jax.config.update("jax_numpy_rank_promotion", "raise")

# The CLI's own on-disk XLA cache (~/.cache/hairjax/xla) stays off in tests.
os.environ["HAIRJAX_CACHE_DIR"] = ""

import pytest  # noqa: E402


@pytest.fixture(scope="session")
def gl_context():
    """The one GL context of the test session (moderngl tests' habit); GL errors are
    checked around every test that uses it."""
    from hairjax.gl import GLUnavailable, get_context

    try:
        return get_context()
    except GLUnavailable as err:
        pytest.skip(f"no OpenGL here: {err}")


@pytest.fixture
def gl(gl_context):
    assert gl_context.error == "GL_NO_ERROR"
    yield gl_context
    assert gl_context.error == "GL_NO_ERROR"
