"""Strict test settings (as optimistix's): float64 on, rank promotion raises."""

import os

import jax

jax.config.update("jax_enable_x64", True)
jax.config.update("jax_numpy_rank_promotion", "raise")

# The CLI's on-disk XLA cache stays off in tests (no writes to the home folder).
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
