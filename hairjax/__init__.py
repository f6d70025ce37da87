"""hairjax: differentiable hair shading in JAX.

Strands are drawn as antialiased, alpha-blended ribbons in a bin-sorted visibility order,
self-shadowed with opacity shadow maps and shaded with Kajiya-Kay or Scheuermann's two
shifted highlights. The model is written down once, in docs/model.md; how the package is
laid out, and how to add a shading model, shadow method or ordering, in
docs/architecture.md.

The package is loaded lazily (PEP 562, with `lazy_loader`): `import hairjax` costs a few
milliseconds, and JAX is imported on the first use of a name that needs it, so
`hairjax --help` answers at once. The public names are listed once, in `__init__.pyi`,
which type checkers read and `lazy_loader.attach_stub` turns into the module's
`__getattr__`, `__dir__` and `__all__`.
"""

from importlib.metadata import PackageNotFoundError, version

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)

try:
    __version__ = version("hairjax")
except PackageNotFoundError:  # running from a source tree without installation
    __version__ = "0+unknown"
