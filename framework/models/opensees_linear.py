"""Stiffness affine in declared parameters: OpenSees matrices extracted once, combined per evaluation.

For parameters theta_p on which the assembled stiffness depends linearly and the mass not at
all (spring stiffnesses, moduli of elastic elements, no gravity analysis),

    K(theta) = K_0 + sum_p (theta_p - theta_0p) K_p,   K_p = (K(theta_0 + h_p e_p) - K_0) / h_p,

with K_0, M at theta_0 (the initial values) and one step h_p = |theta_0p| (or the bound
range if theta_0p = 0) per parameter: P + 1 builds once per process instead of one build
and two dense extractions per evaluation. The declaration is checked when the operators are
extracted: each step must leave M bit-identical and K at theta_0 + 0.37 sum_p h_p e_p must
match the prediction entry by entry to 1e-9 of the entry's magnitude; otherwise every
evaluation that relies on it fails with "nonlinear_parameter".

Results differ from a build per evaluation at the round-off level of K (~1e-12 relative in
the frequencies of the detailed lab frame) and are bit-identical for identical theta in any
process: the extraction points do not depend on what was evaluated before.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from framework.core.errors import ModelEvaluationError

#: relative position of the linearity check point along each step
CHECK_FRACTION = 0.37

#: entry-wise tolerance of the linearity check, relative to the magnitude of the entry's terms
LINEARITY_RTOL = 1e-9


@dataclass(frozen=True)
class LinearOperators:
    """K_0, dK/dtheta_p, M and the measured-DOF rows extracted at ``base`` (all parameter values)."""

    base: Mapping[str, float]
    names: tuple[str, ...]
    k0: np.ndarray
    k_param: np.ndarray  # (P, n, n)
    mass: np.ndarray
    rows: tuple

    def covers(self, values: Mapping[str, float]) -> bool:
        """True when only the linear parameters differ from the extraction point."""
        return all(values[name] == value for name, value in self.base.items() if name not in self.names)

    def stiffness(self, values: Mapping[str, float]) -> np.ndarray:
        """K = K_0 + sum_p (theta_p - theta_0p) K_p (in the order of ``names``)."""
        k = self.k0.copy()
        for name, k_p in zip(self.names, self.k_param):
            step = float(values[name]) - float(self.base[name])
            if step != 0.0:
                k += step * k_p
        return k


def extract_linear_operators(
    extract: Callable[[dict], tuple[np.ndarray, np.ndarray, Sequence]],
    base: Mapping[str, float],
    names: Sequence[str],
    steps: Mapping[str, float],
) -> LinearOperators:
    """Operators from ``extract(values) -> (K, M, measured rows)`` at base and one step per name.

    Raises ModelEvaluationError("nonlinear_parameter") when a step changes M or the numbering,
    or K is not affine in the named parameters (see the module docstring).
    """
    base = dict(base)
    k0, m0, rows = extract(base)
    k_param = []
    for name in names:
        h = float(steps[name])
        k1, m1, rows1 = extract({**base, name: base[name] + h})
        if k1.shape != k0.shape or not _same_rows(rows1, rows):
            raise ModelEvaluationError("nonlinear_parameter", f"{name} changes the equation numbering")
        if not np.array_equal(m1, m0):
            raise ModelEvaluationError("nonlinear_parameter", f"{name} changes the mass matrix")
        k_param.append((k1 - k0) / h)
    op = LinearOperators(base, tuple(names), k0, np.array(k_param).reshape(len(names), *k0.shape), m0, tuple(rows))
    check = {**base, **{name: base[name] + CHECK_FRACTION * float(steps[name]) for name in names}}
    k_check, _, _ = extract(check)
    predicted = op.stiffness(check)
    magnitude = np.abs(k0) + sum(abs(CHECK_FRACTION * float(steps[n])) * np.abs(k) for n, k in zip(names, k_param))
    excess = np.abs(k_check - predicted) - LINEARITY_RTOL * magnitude - 1e-15 * np.abs(k0).max()
    if np.any(excess > 0.0):
        i, j = np.unravel_index(np.argmax(excess), excess.shape)
        raise ModelEvaluationError(
            "nonlinear_parameter",
            f"the stiffness is not linear in {list(names)}: K[{i}, {j}] = {k_check[i, j]:.6g}, "
            f"linear prediction {predicted[i, j]:.6g}",
        )
    return op


def _same_rows(a: Sequence, b: Sequence) -> bool:
    return len(a) == len(b) and all(
        np.array_equal(x.equations, y.equations) and np.array_equal(x.coefficients, y.coefficients)
        for x, y in zip(a, b)
    )
