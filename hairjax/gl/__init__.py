"""The GL renderer: the hair model of docs/model.md on OpenGL (moderngl, headless EGL).

The fast path; `hairjax compare` checks it pixel by pixel against the JAX renderer.
"""

from ._context import GLError as GLError, GLUnavailable as GLUnavailable, get_context as get_context
from ._renderer import GLResult as GLResult, render_gl as render_gl
