"""Standard errors of a fit (docs/fitting.md, "Result, standard errors and undetermined
parameters"): σ²(JᵀJ)⁻¹ at the fit's point, and which parameters the data cannot determine."""

from __future__ import annotations

import numpy as np

from ._solvers import NULL_RATIO

__all__ = ["covariance"]


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
