"""Model evidence of a calibrated candidate by the Laplace approximation (issue 18, our own).

For whitened residuals r(theta) (-2 ln L = chi2 + const) and a uniform prior on the box of
the parameters, at the calibrated optimum theta*:

    ln Z = ln L(theta*) + ln p(theta*) + k/2 ln(2 pi) - 1/2 ln det H,
    ln L(theta*) = -chi2_min / 2 (the constant, the same for every model of one data set,
    dropped), ln p = -sum_i ln(upper_i - lower_i) - ln V,

with H = J' J the Gauss-Newton Hessian of -ln L (J = dr/dtheta in physical units, central
differences at 1e-3 of each parameter's span, one-sided at a bound) and V the number of
variants searched (a uniform prior over the locations); a parameter on which the residuals
do not depend (a zero Jacobian column) integrates its prior to 1 and is left out. 2 (ln Z_1 - ln Z_0) is on the
scale of -Delta BIC; an effect is decisive by the evidence when it beats no change and the
runner-up by ``DECISIVE_2LNB`` = 10 (2 ln Bayes factor, Kass & Raftery: very strong).
The approximation assumes an interior, Gaussian-shaped optimum: a parameter at its bound
(flagged in the tables) makes it approximate.

The Laplace formula itself is :func:`framework.inference.evidence.laplace_log_evidence`
(issue 18, tag ``linearized-ready``, merged); this module adds the discrepancy workflow's
use of it: the finite-difference Jacobian at a candidate's fit, the prior over the
locations and the parameters without influence. A singular H otherwise gives NaN.
"""

from __future__ import annotations

import math

import numpy as np

from framework.inference.evidence import laplace_log_evidence as uq_laplace
from framework.updating.problem import UpdatingProblem

DECISIVE_2LNB = 10.0
FD_STEP = 1e-3


def fd_jacobian(problem: UpdatingProblem, x: np.ndarray, step: float = FD_STEP) -> np.ndarray:
    """dr/dx (r, k) at the normalized point x by central differences (one-sided at a bound)."""
    x = np.asarray(x, float)
    k = x.size
    lo = np.clip(x - step, 0.0, 1.0)
    hi = np.clip(x + step, 0.0, 1.0)
    pts = []
    for i in range(k):
        a, b = x.copy(), x.copy()
        a[i], b[i] = lo[i], hi[i]
        pts += [a, b]
    ev = problem.evaluate(np.array(pts))
    r = ev.residuals
    jac = np.empty((r.shape[1], k))
    for i in range(k):
        jac[:, i] = (r[2 * i + 1] - r[2 * i]) / max(hi[i] - lo[i], 1e-12)
    return jac


def laplace_log_evidence(chi2: float, jac_x: np.ndarray, spans: np.ndarray, n_variants: int = 1) -> float:
    """ln Z of the module docstring from chi2_min and J in normalized x (J_theta = J_x / span)."""
    spans = np.asarray(spans, float)
    norms = np.linalg.norm(jac_x, axis=0) if jac_x.size else np.zeros(0)
    keep = norms > 1e-8 * max(float(norms.max(initial=0.0)), 1e-300)
    # a parameter the residuals do not depend on: the likelihood is flat over its prior range,
    # whose integral cancels its prior density (it contributes 0 to ln Z)
    spans, jac_x = spans[keep], jac_x[:, keep]
    k = spans.size
    log_prior = -float(np.sum(np.log(spans))) - math.log(max(n_variants, 1))
    if k == 0:
        return -0.5 * chi2 + log_prior
    return uq_laplace(-0.5 * chi2, log_prior, jac_x.T @ jac_x, spans)
