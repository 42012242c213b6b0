"""Relative sensitivities of paired frequencies and MACs to the parameters, and what they
imply for identifiability.

With a forward difference of relative step h on parameter p_j (n + 1 model runs):

    S_f[i, j]   = ((f_i(p + h p_j e_j) - f_i(p)) / f_i(p)) / h      (df/f per dp/p)
    S_MAC[i, j] = (MAC_i(p + h p_j e_j) - MAC_i(p)) / h             (dMAC per dp/p)

(a parameter whose value is 0 is stepped by h times its bound width and reported per
that absolute step). A step must not be clipped at a bound of the normalized box: by
default a forward step that would leave the upper bound is taken backwards (a backward
difference); with ``widen=(lo, hi)`` the evaluation uses bounds [lo, hi] x initial
instead (e.g. (0.01, 2)), so every step stays forward. The n + 1 points go through
``problem.evaluate`` in one call (any runner); they are not optimizer evaluations and
are counted nowhere.

From the stacked matrix S = [S_f; S_MAC]: singular values, condition number s_max / s_min,
and the parameter correlation implied by a linearized least-squares fit,
C = (S^T S)^+, rho_jk = C_jk / sqrt(C_jj C_kk); |rho| near 1 means the data cannot tell
the two parameters apart.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from framework.core.errors import InputError, ModelEvaluationError


@dataclass(frozen=True)
class SensitivityResult:
    parameters: list[str]
    modes: list[str]
    frequency: np.ndarray  # (m, k)
    mac: np.ndarray  # (m, k)
    singular_values: np.ndarray
    condition_number: float
    correlation: np.ndarray  # (k, k)
    theta0: np.ndarray  # (k,) physical point of the derivatives
    f_model_hz: np.ndarray  # (m,) frequencies of the paired modes at theta0
    rel_step: float

    def table(self) -> pd.DataFrame:
        """Tidy: one row per quantity, mode and parameter."""
        rows = []
        for q, S in (("frequency", self.frequency), ("mac", self.mac)):
            for i, mode in enumerate(self.modes):
                for j, p in enumerate(self.parameters):
                    rows.append({"quantity": q, "mode": i + 1, "label": mode, "parameter": p,
                                 "sensitivity": float(S[i, j])})
        return pd.DataFrame(rows)

    def correlation_table(self) -> pd.DataFrame:
        return pd.DataFrame(self.correlation, index=self.parameters, columns=self.parameters)


def sensitivity_matrix(
    problem,
    theta0: np.ndarray | None = None,
    rel_step: float = 1e-3,
    include_mac: bool = True,
    widen: tuple[float, float] | None = None,
    runner=None,
) -> SensitivityResult:
    """Forward-difference relative sensitivities at physical point theta0 (default: initial).

    widen: evaluate with bounds [lo, hi] x initial (so no step is clipped, every step
    forward) instead of the problem's own bounds.
    """
    if widen is not None:
        problem = _widened(problem, widen)
    params = problem.parameters
    theta0 = params.initial.copy() if theta0 is None else np.asarray(theta0, float)
    points = [theta0]
    steps = []
    for j, p in enumerate(params):
        t = theta0.copy()
        step = rel_step * theta0[j] if theta0[j] != 0 else rel_step * p.span
        if t[j] + step > p.upper:
            step = -step
        t[j] += step
        points.append(t)
        steps.append(step)
    X = params.to_normalized(np.array(points))
    if np.any(X < -1e-12) or np.any(X > 1 + 1e-12):
        raise InputError(f"sensitivity point theta0={theta0.tolist()} or its steps lie outside the bounds; "
                         "give widen=(lo, hi)")  # fmt: skip
    ev = problem.evaluate(np.clip(X, 0.0, 1.0), runner)
    if not ev.ok.all():
        bad = int(np.flatnonzero(~ev.ok)[0])
        raise ModelEvaluationError(ev.reasons[bad] or "failed", f"sensitivity point {bad} failed")
    base = ev.correlations[0]
    f0 = base.f_model_hz
    k, m = len(params), problem.measured.n_modes
    S_f = np.zeros((m, k))
    S_mac = np.zeros((m, k))
    for j in range(k):
        c = ev.correlations[j + 1]
        h = steps[j] / theta0[j] if theta0[j] != 0 else rel_step
        S_f[:, j] = (c.f_model_hz - f0) / f0 / h
        if include_mac and np.isfinite(base.mac).any():
            S_mac[:, j] = (c.mac - base.mac) / h
    S = np.vstack([S_f, S_mac]) if include_mac and np.isfinite(base.mac).any() else S_f
    S = np.nan_to_num(S)
    sv = np.linalg.svd(S, compute_uv=False)
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
    C = np.linalg.pinv(S.T @ S)
    d = np.sqrt(np.clip(np.diag(C), 1e-300, None))
    rho = C / np.outer(d, d)
    return SensitivityResult(
        params.names, list(problem.measured.labels), S_f, S_mac, sv, cond, rho, theta0, np.asarray(f0, float), rel_step
    )


def _widened(problem, widen: tuple[float, float]):
    """The same problem with bounds widened to include [lo, hi] x initial for every parameter
    (not 0 initially); the problem's own bounds stay inside, so any point of the box is valid."""
    from framework.updating.problem import UpdatingProblem

    lo, hi = widen
    if not 0 <= lo < 1 < hi:
        raise InputError(f"sensitivity: widen must be (lo, hi) with 0 <= lo < 1 < hi, got {widen!r}")
    bounds = {p.name: (min(lo * p.initial, hi * p.initial, p.lower), max(lo * p.initial, hi * p.initial, p.upper))
              for p in problem.parameters if p.initial != 0}
    parameters = problem.parameters.with_bounds(bounds)
    return UpdatingProblem(problem.model, problem.measured, parameters, problem.spec, name=problem.name)
