"""Model evidence by the Laplace approximation (the nested-sampling estimate is in
:mod:`framework.inference.sampling`).

    ln Z = ln L(theta*) + ln p(theta*) + k/2 ln(2 pi) - 1/2 ln det H_theta,

H_theta = J_theta' Sigma^-1 J_theta (+ the prior's Hessian) the Gauss-Newton Hessian of
-ln p(theta | data) at the optimum theta*. From H_x in normalized coordinates (x = (theta -
lower) / span): ln det H_theta = ln det H_x - 2 sum ln span. The approximation assumes a
Gaussian posterior well inside the bounds; with a singular H (a direction the data do not
determine) it does not exist and NaN is returned.
"""

from __future__ import annotations

import numpy as np


def laplace_log_evidence(log_likelihood: float, log_prior: float, hessian_x: np.ndarray, span: np.ndarray) -> float:
    """ln Z of the Laplace approximation (module docstring); NaN when H_x is singular."""
    sign, logdet_x = np.linalg.slogdet(np.asarray(hessian_x, float))
    if sign <= 0 or not np.isfinite(logdet_x):
        return float("nan")
    k = len(span)
    logdet = logdet_x - 2.0 * float(np.sum(np.log(span)))
    return float(log_likelihood + log_prior + 0.5 * k * np.log(2.0 * np.pi) - 0.5 * logdet)
