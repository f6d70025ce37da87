"""`hairjax.fit`: shading parameters fitted to target images with optimistix (docs/fitting.md).

One concept per module: `_entry` (`fit`), `_result` (FitResult, FitError), `_space` (the
solver's parameter space), `_problem` (targets, weights, the residuals), `_varpro` and
`_nnls` (the gains solved for), `_solvers`, `_convergence` (the solve loop),
`_uncertainty` (standard errors), `_model` (what a shading model provides), and one module
per shading model: `_kajiya_kay`, `_scheuermann`.
"""

from ._entry import fit
from ._kajiya_kay import FITTABLE
from ._result import FitError, FitResult
from ._scheuermann import SCHEUERMANN_FITTABLE
from ._solvers import SOLVERS

__all__ = ["fit", "FitResult", "FitError", "FITTABLE", "SOLVERS", "SCHEUERMANN_FITTABLE"]
