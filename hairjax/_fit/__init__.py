"""`hairjax.fit`: shading parameters fitted to target images with optimistix (docs/fitting.md).

One concept per module: `_entry` (`fit`), `_result` (FitResult, FitError), `_space` (the
solver's parameter space), `_problem` (targets, weights, the residuals), `_varpro` and
`_nnls` (the gains solved for), `_solvers`, `_convergence` (the solve loop),
`_uncertainty` (standard errors), `_model` (what the fit asks of a shading model) and
`_shading_fit` (that, for any registered shading model, from the model's own terms), with
`_dependence` (which images a fitted parameter reaches); `_lit` and `_light_fit` add the
light's direction and colour to a fit, `_point` and `_opacity_fit` the strands' opacity;
`_holdout` reports the fit on held-out targets; `_options` holds the records `fit` takes
(FitTargets, FitVariables, FitStop).
"""

from ._entry import fit as fit
from ._holdout import fitted_image as fitted_image
from ._lit import LIGHT_NAMES as LIGHT_NAMES
from ._opacity_fit import ALPHA as ALPHA
from ._options import FitStop as FitStop
from ._options import FitTargets as FitTargets
from ._options import FitVariables as FitVariables
from ._result import FitError as FitError
from ._result import FitNotConverged as FitNotConverged
from ._result import FitResult as FitResult
from ._solvers import BFGS as BFGS
from ._solvers import SOLVERS as SOLVERS
from ._solvers import GaussNewton as GaussNewton
from ._solvers import fit_solvers as fit_solvers
from ._solvers import solver_named as solver_named
