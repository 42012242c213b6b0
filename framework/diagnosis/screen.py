"""Cheap screening of an effect's variants before calibration (``settings.screen_keep``).

Calibrating every location of every candidate costs one least-squares fit per variant
(hundreds on a model with hundreds of elements). The screen ranks the variants by a
linearized fit instead and calibrates only the ``screen_keep`` best of each effect.

Rule: at the current calibrated model (normalized x_0, residuals r_0), the Jacobian J_b of
the residuals with respect to the current parameters is computed once per round (forward
differences) and P = I - J_b J_b^+ projects out what re-adjusting them can fit. For each
variant, each effect parameter alone is set to trial values 1/8, 1/4, 1/2 and 1 of the way
from its null value to each bound that is not the null value (current parameters at x_0),
and the residuals r_t evaluated; along each such axis the residuals are interpolated
linearly between the null value (r_0) and the trials, and the variant's score is the
smallest linearized chi2 on that path,

    chi2_lin = min over the path of || P r(phi) ||^2    (closed form per segment),

(a Gauss-Newton step of the base parameters; the effect's own nonlinearity is sampled,
not linearized, since masses and springs act nonlinearly). Cost: 4 model evaluations per
direction per variant plus k_base + 1 per round, against ~50-150 for a calibration. The number of variants
searched still enters the BIC (2 ln V): the screen is part of the search.
"""

from __future__ import annotations

import numpy as np

from framework.diagnosis.effects import Effect
from framework.updating.problem import UpdatingProblem

#: trial positions, as fractions of the way from the null value to a bound
TRIAL_FRACTIONS = (0.125, 0.25, 0.5, 1.0)


def trial_axes(effect: Effect) -> list[list[dict[str, float]]]:
    """Per parameter and direction, the trial points ordered away from the null value."""
    axes = []
    for p in effect.parameters:
        for bound in (p.lower, p.upper):
            if bound != p.initial:
                axes.append([{p.name: p.initial + f * (bound - p.initial)} for f in TRIAL_FRACTIONS])
    return axes


def segment_minimum(ra: np.ndarray, rb: np.ndarray) -> float:
    """min over t in [0, 1] of ||ra + t (rb - ra)||^2 (closed form)."""
    d = rb - ra
    dd = float(d @ d)
    t = 0.0 if dd == 0 else float(np.clip(-(ra @ d) / dd, 0.0, 1.0))
    r = ra + t * d
    return float(r @ r)


def base_projector(problem: UpdatingProblem, x0: np.ndarray, step: float = 1e-3) -> np.ndarray:
    """I - J_b J_b^+ of the current model's residuals at x0 (forward differences)."""
    x0 = np.asarray(x0, float)
    k = x0.size
    pts = [x0]
    steps = []
    for i in range(k):
        x = x0.copy()
        h = step if x0[i] + step <= 1.0 else -step
        x[i] += h
        pts.append(x)
        steps.append(h)
    r = problem.evaluate(np.array(pts)).residuals
    jac = (r[1:] - r[0]).T / np.array(steps)[None, :]
    q, s, _ = np.linalg.svd(jac, full_matrices=False)
    q = q[:, s > 1e-10 * max(s.max(initial=0.0), 1e-300)]
    return np.eye(r.shape[1]) - q @ q.T


def screen_scores(model, measured, params, x_base: dict[str, float], effect: Effect, projector: np.ndarray,
                  spec, r_null: np.ndarray) -> tuple[float, int]:  # fmt: skip
    """(chi2_lin of the module docstring, evaluations) of one variant's model; r_null: the
    current fit's residuals (the enriched model at the effect's null value)."""
    problem = UpdatingProblem(model, measured, parameters=params, objective=spec)
    axes = trial_axes(effect)
    pts = []
    for axis in axes:
        for trial in axis:
            theta = dict(x_base) | trial
            pts.append(params.to_normalized(np.array([theta[n] for n in params.names])))
    if not pts:  # an effect without parameters: its model at the current base values
        pts.append(params.to_normalized(np.array([x_base[n] for n in params.names])))
        axes = [[{}]]
    r = problem.evaluate(np.array(pts)).residuals
    n = projector.shape[0]
    lin = np.einsum("ij,tj->ti", projector, r[:, :n])
    extra = np.sum(r[:, n:] ** 2, axis=1)
    best = float(np.min(np.sum(lin**2, axis=1) + extra))
    start = projector @ r_null[:n]
    i = 0
    for axis in axes:  # piecewise-linear residuals along each axis, from the null value outwards
        prev = start
        for _ in axis:
            best = min(best, segment_minimum(prev, lin[i]) + float(extra[i]))
            prev = lin[i]
            i += 1
    return best, len(pts)
