"""`hairjax.fit`: shading parameters fitted to target images with optimistix (docs/fitting.md)."""

from ._entry import FITTABLE, SOLVERS, fit
from ._result import FitError, FitResult
from ._scheuermann import SCHEUERMANN_FITTABLE

__all__ = ["fit", "FitResult", "FitError", "FITTABLE", "SOLVERS", "SCHEUERMANN_FITTABLE"]
