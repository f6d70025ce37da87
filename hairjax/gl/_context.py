"""The one place that creates the OpenGL context, and GL error checks.

A headless EGL context (Mesa's llvmpipe without a GPU, the vendor driver with one),
created once per process and cached.
"""

from __future__ import annotations

import functools

__all__ = [
    "GLUnavailable",
    "GLError",
    "get_context",
    "renderer_info",
    "check",
    "release",
    "SYSTEM_PACKAGES",
]

# What Debian needs for a headless EGL context (the Makefile installs them when missing).
SYSTEM_PACKAGES = "libegl1 libgl1-mesa-dri"
MIN_GL_VERSION = 450  # compute shaders, SSBOs, geometry shaders: OpenGL 4.5 (llvmpipe has it)


class GLUnavailable(RuntimeError):
    """No usable OpenGL: the message says what is missing and what to install."""


class GLError(RuntimeError):
    """A GL call failed, or a shader did not compile (the message names it)."""


@functools.cache
def get_context():
    """The process's headless moderngl context (created on first use)."""
    try:
        import moderngl
    except ImportError as err:  # pragma: no cover - moderngl is a dependency
        raise GLUnavailable(f"moderngl is not installed: {err}") from err
    try:
        # `require` is the version EGL is asked for: NVIDIA's driver gives the 3.3 core
        # context moderngl asks for by default, and 4.5 only when asked.
        ctx = moderngl.create_context(standalone=True, backend="egl", require=MIN_GL_VERSION)
    except Exception as err:
        raise GLUnavailable(
            f"cannot create a headless OpenGL {MIN_GL_VERSION // 100}.{MIN_GL_VERSION // 10 % 10} "
            f"context through EGL ({err}). On Debian/Ubuntu "
            f"install the system packages: apt-get install {SYSTEM_PACKAGES}. The JAX "
            "renderer (--backend jax) works without OpenGL."
        ) from err
    if ctx.version_code < MIN_GL_VERSION:
        version = ctx.info.get("GL_VERSION", ctx.version_code)
        ctx.release()
        raise GLUnavailable(
            f"OpenGL {MIN_GL_VERSION // 100}.{MIN_GL_VERSION // 10 % 10} is needed, this "
            f"driver offers {version}. Mesa's llvmpipe ({SYSTEM_PACKAGES}) provides 4.5."
        )
    check(ctx, "context creation")
    return ctx


def renderer_info() -> dict[str, str]:
    """The driver behind the context, as GL names it: `gl_renderer` (e.g. "llvmpipe (LLVM
    15.0.6, 256 bits)" without a GPU, the card's name with its vendor's driver) and
    `gl_version`. Raises `GLUnavailable` where there is no context."""
    info = get_context().info
    return {"gl_renderer": str(info.get("GL_RENDERER")), "gl_version": str(info.get("GL_VERSION"))}


def check(ctx, stage: str) -> None:
    """Raise `GLError` naming `stage` if GL recorded an error."""
    error = ctx.error
    if error != "GL_NO_ERROR":
        raise GLError(f"OpenGL error after {stage}: {error}")


@functools.cache
def _home_framebuffer(ctx):
    """A 1 × 1 framebuffer that outlives every pass: bound before a pass's own framebuffer
    is released, so moderngl never restores a deleted framebuffer binding (which GL
    reports as GL_INVALID_OPERATION at the next framebuffer creation)."""
    return ctx.framebuffer(color_attachments=[ctx.renderbuffer((1, 1))])


def release(ctx, *objects) -> None:
    """Release GL objects of a finished pass, leaving valid bindings behind."""
    _home_framebuffer(ctx).use()
    for obj in objects:
        if obj is not None:
            obj.release()
