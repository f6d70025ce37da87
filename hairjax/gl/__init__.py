"""The GL renderer: the hair model of docs/model.md on OpenGL (moderngl, headless EGL).

The fast path; `hairjax compare` checks it pixel by pixel against the JAX renderer.
"""

from ._context import GLError as GLError
from ._context import GLUnavailable as GLUnavailable
from ._context import get_context as get_context
from ._context import renderer_info as renderer_info
from ._occluder import OccluderLight as OccluderLight
from ._occluder import occluder_light as occluder_light
from ._renderer import GLResult as GLResult
from ._renderer import render_gl as render_gl
