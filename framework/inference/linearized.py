"""Linearized (Gaussian) posterior at the optimum from the Jacobian of the residual vector.

With whitened residuals r_w = r / s (:class:`~framework.inference.likelihood.NoiseModel`)
and their Jacobian J_w = dr_w/dx in the normalized coordinates x (``UpdatingProblem.jacobian``:
exact from modal derivatives where available, else forward differences), the Gauss-Newton
Hessian of -ln p(x | data) is

    H_x = J_w' J_w + D P D,   D = diag(upper - lower), P the prior's Hessian in theta,

and the posterior is approximated by N(theta*, C), C = D H_x^+ D (pseudo-inverse: a direction
with no information gets the prior's width in the uniform case only through the bounds,
which this approximation ignores; such a direction is named by the identifiability table).
Standard deviations sqrt(diag C), correlations C_ij / (sd_i sd_j) and 90 % intervals
theta* +- 1.645 sd (not clipped to the bounds: an interval beyond a bound shows that the
Gaussian approximation does not hold there).

Identifiability: the singular values sigma_j and right singular vectors v_j of J_w in x. A
combination v_j' x is determined to a standard deviation 1 / sigma_j, in fractions of the
bound spans; the prior (uniform on the bounds) alone gives 1 / sqrt(12) = 0.29, so
``information_ratio`` = (1 / sigma_j) / 0.29 near or above 1 means the data do not determine
that combination.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import norm

UNIFORM_STD = 1.0 / np.sqrt(12.0)


@dataclass(frozen=True)
class LinearizedPosterior:
    """Gaussian approximation of the posterior in physical units (module docstring)."""

    names: list[str]
    theta: np.ndarray          # (k,) the optimum
    covariance: np.ndarray     # (k, k) in physical units
    hessian_x: np.ndarray      # (k, k) H_x in normalized coordinates
    singular_values: np.ndarray  # (k,) of J_w (descending)
    directions: np.ndarray     # (k, k) rows = right singular vectors v_j in x
    jacobian_method: str

    @property
    def std(self) -> np.ndarray:
        return np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))

    @property
    def correlation(self) -> np.ndarray:
        sd = self.std
        with np.errstate(divide="ignore", invalid="ignore"):
            return self.covariance / np.outer(sd, sd)

    def interval(self, level: float = 0.9) -> tuple[np.ndarray, np.ndarray]:
        z = norm.ppf(0.5 + level / 2.0)
        return self.theta - z * self.std, self.theta + z * self.std

    def identifiability_rows(self) -> list[dict]:
        """One row per singular direction: singular value, std along it (fraction of the
        spans), its ratio to the uniform prior's, the dominant parameter and the combination."""
        rows = []
        for j, (sv, v) in enumerate(zip(self.singular_values, self.directions)):
            std_x = 1.0 / sv if sv > 0 else np.inf
            order = np.argsort(-np.abs(v))
            text = " ".join(f"{v[i]:+.2f} {self.names[i]}" for i in order if abs(v[i]) >= 0.05)
            rows.append({"direction": j + 1, "singular_value": float(sv), "std_normalized": float(std_x),
                         "information_ratio": float(std_x / UNIFORM_STD),
                         "dominant_parameter": self.names[int(order[0])], "combination": text})
        return rows


def linearized_posterior(J_x: np.ndarray, scales: np.ndarray, parameters, theta: np.ndarray,
                         prior_hessian: np.ndarray | None = None, method: str = "") -> LinearizedPosterior:
    """The linearized posterior from the Jacobian J_x (r, k) of the residuals in normalized x
    (only the first len(scales) rows, the modal residuals, are data)."""
    J_w = np.asarray(J_x, float)[: scales.size] / scales[:, None]
    span = parameters.upper - parameters.lower
    H = J_w.T @ J_w
    if prior_hessian is not None:
        H = H + span[:, None] * prior_hessian * span[None, :]
    C_x = np.linalg.pinv(H, hermitian=True)
    _, s, Vt = np.linalg.svd(J_w, full_matrices=False)
    k = J_w.shape[1]
    if s.size < k:  # fewer residuals than parameters: the missing directions carry no information
        _, _, Vt_full = np.linalg.svd(np.vstack([J_w, np.zeros((k - s.size, k))]))
        s, Vt = np.r_[s, np.zeros(k - s.size)], Vt_full
    C = span[:, None] * C_x * span[None, :]
    return LinearizedPosterior(list(parameters.names), np.asarray(theta, float), C, H, s, Vt, method)


def at_optimum(problem, x: np.ndarray, noise, prior=None, runner=None) -> LinearizedPosterior:
    """Linearized posterior of ``problem`` at the normalized optimum x: one Jacobian
    (``problem.jacobian``: exact where the model provides derivatives, else forward differences)."""
    jac = problem.jacobian(np.asarray(x, float), runner)
    if jac.method == "failed" or jac.J is None:
        raise RuntimeError(f"Jacobian failed at the optimum: {jac.reason}")
    theta = problem.parameters.to_physical(np.asarray(x, float))
    return linearized_posterior(jac.J, noise.scales, problem.parameters, theta,
                                None if prior is None else prior.hessian(), jac.method)
