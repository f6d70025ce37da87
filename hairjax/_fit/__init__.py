"""`hairjax.fit`: shading parameters fitted to target images with optimistix (docs/fitting.md)."""

from ._entry import FITTABLE, SOLVERS, FitError, FitResult, fit
from ._scheuermann import SCHEUERMANN_FITTABLE

__all__ = ["fit", "FitResult", "FitError", "FITTABLE", "SOLVERS", "SCHEUERMANN_FITTABLE"]
