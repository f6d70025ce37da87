"""Standard errors of a fit (docs/fitting.md, "Result, standard errors and undetermined
parameters"): σ²(JᵀJ)⁻¹ at the fit's point, and which parameters the data cannot determine."""

from __future__ import annotations

import equinox as eqx
import jax
import numpy as np

from ._lit import RelativeTransform
from ._model import FitModel
from ._problem import residuals_at
from ._solvers import NULL_RATIO
from ._space import error_space, from_flat, to_flat, unflatten

__all__ = ["covariance", "error_jacobian", "standard_errors"]


def covariance(jac, r):
    """From J and r at a fit's point: (σ²·diag (JᵀJ)⁺ over the determined directions, which
    entries have weight in an undetermined one), σ² = ‖r‖²/(m − n); None where J or r is not
    finite. A direction is undetermined when its JᵀJ eigenvalue is ≤ NULL_RATIO²·λ_max
    (numerically singular) or ≤ m·1e-12 (one unit along it moves the m residuals by under
    1e-6 RMS, below float32 resolution of an image)."""
    jac, r = np.asarray(jac, dtype=np.float64), np.asarray(r, dtype=np.float64)
    if not (np.all(np.isfinite(jac)) and np.all(np.isfinite(r))):
        # Fires at a point where the image or its derivatives overflow: nothing is known.
        return None
    m, n = jac.shape
    evals, evecs = np.linalg.eigh(jac.T @ jac)
    # (The 1e-300 fires for J = 0: every direction is then undetermined.)
    null = (evals <= NULL_RATIO**2 * max(evals.max(initial=0.0), 1e-300)) | (evals <= m * 1e-12)
    # (The 1 fires with no more residuals than unknowns: σ² is then ‖r‖², not a mean.)
    sigma2 = float(r @ r) / max(m - n, 1)
    var = sigma2 * np.diag((evecs[:, ~null] / evals[~null]) @ evecs[:, ~null].T)
    in_null = (np.abs(evecs[:, null]) > 0.1).any(axis=1) if null.any() else np.zeros(n, bool)
    return var, in_null


@eqx.filter_jit
def error_jacobian(u, fitted, model: FitModel, data, names, scalar):
    """J and r of the residuals in the standard errors' space (`error_space`) at u."""
    space = error_space(model.transforms)

    def residuals(u):
        return residuals_at(model, from_flat(u, fitted, names, model.colours, scalar, space), data)

    return jax.jacfwd(residuals)(u), residuals(u)


def standard_errors(model: FitModel, data, fitted, names, scalar):
    """(name → standard error, the names without one) from σ²(JᵀJ)⁻¹, J taken in the
    gains themselves and in the solver's space for the rest (log exponents and κ, shifts as
    they are), mapped to the parameters by the transforms' derivatives (delta method).
    Parameters with weight in a direction the data do not determine (`covariance`: one unit
    along it, an e-fold of an exponent or κ or a unit of gain, moves the residuals by under
    1e-6 RMS, or it is numerically singular) get no error. An RGB parameter's error is an
    array of 3, a grey value's or a scalar's a float. The light's direction has one error,
    an angle in radians: J is taken in its tangent plane at the fitted direction
    (`_lit.PLANE`), where (a, b) are the angles along e₁, e₂ to first order, and the error
    is √(σ_a² + σ_b²), the RMS angle between the fitted direction and the truth."""
    space = error_space(model.transforms)
    flat = to_flat(fitted, names, scalar, space)
    cov = covariance(*error_jacobian(flat, fitted, model, data, tuple(names), tuple(scalar)))
    if cov is None:
        return {name: None for name in names}, tuple(names)
    var_u, in_null = cov
    u = unflatten(flat, names, model.colours, scalar, space)
    std: dict[str, np.ndarray | float | None] = {}
    undetermined: list[str] = []
    i = 0
    for name in names:
        size = int(np.size(u[name]))
        sl, i = slice(i, i + size), i + size
        if in_null[sl].any():
            std[name] = None
            undetermined.append(name)
            continue
        if isinstance(space[name], RelativeTransform):
            std[name] = float(np.sqrt(np.sum(np.maximum(var_u[sl], 0.0))))
            continue
        dxdu = np.asarray(jax.vmap(jax.grad(space[name].forward))(u[name]))
        se = np.abs(dxdu) * np.sqrt(np.maximum(var_u[sl], 0.0))
        std[name] = se if size > 1 else float(se[0])
    return std, tuple(undetermined)
