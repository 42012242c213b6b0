"""Model evidence by the Laplace approximation (the nested-sampling estimate is in
:mod:`framework.inference.sampling`).

    ln Z = ln L(theta*) + ln p(theta*) + k/2 ln(2 pi) - 1/2 ln det H_theta,

H_theta = J_theta' Sigma^-1 J_theta (+ the prior's Hessian) the Gauss-Newton Hessian of
-ln p(theta | data) at the optimum theta*. From H_x in normalized coordinates (x = (theta -
lower) / span): ln det H_theta = ln det H_x - 2 sum ln span. The approximation assumes a
Gaussian posterior well inside the bounds; with a singular H (a direction the data do not
determine) it does not exist and NaN is returned.

:func:`laplace_log_evidence_chi2` is the same for whitened residuals with the constant of the
likelihood dropped, a prior over the alternatives searched and parameters without influence
left out (the diagnosis's ranking of candidate effects).
"""

from __future__ import annotations

import math

import numpy as np


def laplace_log_evidence(log_likelihood: float, log_prior: float, hessian_x: np.ndarray, span: np.ndarray) -> float:
    """ln Z of the Laplace approximation (module docstring); NaN when H_x is singular."""
    sign, logdet_x = np.linalg.slogdet(np.asarray(hessian_x, float))
    if sign <= 0 or not np.isfinite(logdet_x):
        return float("nan")
    k = len(span)
    logdet = logdet_x - 2.0 * float(np.sum(np.log(span)))
    return float(log_likelihood + log_prior + 0.5 * k * np.log(2.0 * np.pi) - 0.5 * logdet)


def laplace_log_evidence_chi2(chi2: float, jac_x: np.ndarray, span: np.ndarray, n_variants: int = 1) -> float:
    """ln Z of whitened residuals (-2 ln L = chi2 + const, the constant dropped: it is the same
    for every model of one data set) under a uniform prior on the bounds and over ``n_variants``
    alternatives searched (e.g. the locations of an effect): ln L = -chi2 / 2,
    ln p = -sum ln span - ln n_variants and H_x = J_x' J_x (J_x: the Jacobian of the whitened
    residuals in x, e.g. from ``UpdatingProblem.jacobian``). A parameter the residuals do not
    depend on (a zero Jacobian column) has a flat likelihood over its prior range, whose
    integral cancels its prior density: it is left out (contributes 0). NaN when H is singular."""
    span = np.asarray(span, float)
    jac_x = np.asarray(jac_x, float)
    norms = np.linalg.norm(jac_x, axis=0) if jac_x.size else np.zeros(0)
    keep = norms > 1e-8 * max(float(norms.max(initial=0.0)), 1e-300)
    span, jac_x = span[keep], jac_x[:, keep]
    log_prior = -float(np.sum(np.log(span))) - math.log(max(n_variants, 1))
    if span.size == 0:
        return -0.5 * chi2 + log_prior
    return laplace_log_evidence(-0.5 * chi2, log_prior, jac_x.T @ jac_x, span)
