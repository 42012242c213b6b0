"""Damage estimation helpers (SPEC 7): simulated noisy measurements, damage index, detection,
L-curve corner for Tikhonov regularization, the two-state transform of two problems
(NSGA-II on both states at once) and the least-squares polish of a global search's result.

- Shape noise:    phi_jk,measured = phi_jk (1 + a eps_jk), eps_jk ~ U[-1, 1] drawn from
                  ``np.random.default_rng(seed)``, one draw (n_dof, m) per seed;
                  frequencies are left noise-free (SPEC 7: noise only on shapes); the
                  kind :class:`framework.inference.simulate.UniformShapeNoise` of the one
                  simulator of noisy modes.
- Damage index:   D_e = 1 - r_e / r_e,0 (relative loss of the element's I).
- Detection:      element reported damaged when D_e > threshold; a false detection is an
                  element with no true damage reported damaged.
- L-curve corner: maximum curvature (Hansen) of (log ||r||, log ||z - z0||) as functions of log tau.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from framework.core.errors import InputError
from framework.core.parameters import Parameter, ParameterSet
from framework.inference.simulate import UniformShapeNoise
from framework.inference.simulate import noisy_measurement as simulated
from framework.measured.modes import MeasuredModes
from framework.models.base import ModalResult
from framework.updating.problem import Evaluations, as_points

log = logging.getLogger(__name__)

#: damage index above which an element is reported damaged (5 % loss of I; our choice, the
#: source gives none); the default of the beam study's analysis (report.damage_summary.threshold)
DETECTION_THRESHOLD = 0.05


# ---- simulated measurement ---------------------------------------------------------------
def noisy_measurement(
    modes: ModalResult, noise_fraction: float, seed: int, name: str = "simulated", n_modes: int | None = None
) -> MeasuredModes:
    """MeasuredModes from model modes (SPEC 7): exact frequencies, shapes scaled to a largest
    component of +1 with multiplicative noise phi (1 + a eps), eps ~ U[-1, 1], a =
    ``noise_fraction``, from ``np.random.default_rng(seed)`` (:mod:`framework.inference.simulate`)."""
    m = modes.n_modes if n_modes is None else int(n_modes)
    if not 1 <= m <= modes.n_modes:
        raise InputError(f"n_modes must be in [1, {modes.n_modes}], got {n_modes!r}")
    return simulated(modes.frequencies_hz[:m], modes.shapes[:, :m], modes.dofs, UniformShapeNoise(noise_fraction),
                     np.random.default_rng(seed), labels=tuple(f"bending {j + 1}" for j in range(m)), name=name,
                     source=f"simulated:{name}", meta={"noise_fraction": float(noise_fraction), "seed": int(seed)})


# ---- damage index and detection -----------------------------------------------------------
def damage_index(ratio: np.ndarray, ratio_initial: np.ndarray | float = 1.0) -> np.ndarray:
    """D = 1 - r / r0 (positive = stiffness loss)."""
    return 1.0 - np.asarray(ratio, dtype=float) / np.asarray(ratio_initial, dtype=float)


def detected(ratio: np.ndarray, threshold: float = DETECTION_THRESHOLD, ratio_initial=1.0) -> np.ndarray:
    """True where the damage index exceeds ``threshold``."""
    return damage_index(ratio, ratio_initial) > threshold


def false_detections(
    ratio: np.ndarray, truth: np.ndarray, threshold: float = DETECTION_THRESHOLD, ratio_initial=1.0
) -> np.ndarray:
    """True where an element without true damage (truth == initial) is reported damaged."""
    undamaged = np.isclose(np.asarray(truth, float), ratio_initial)
    return undamaged & detected(ratio, threshold, ratio_initial)


# ---- L-curve ------------------------------------------------------------------------------
def lcurve_curvature(
    tau: Sequence[float], residual_norm: Sequence[float], solution_norm: Sequence[float]
) -> np.ndarray:
    """Curvature of the L-curve (Hansen): the parametric curve (rho(t), eta(t)) with
    rho = log10 ||r||, eta = log10 ||z - z0|| and t = log10 tau,

        kappa = (rho' eta'' - rho'' eta') / (rho'^2 + eta'^2)^(3/2),

    derivatives by second-order finite differences in t (``numpy.gradient``, uneven spacing
    allowed). kappa > 0 where the curve bends towards the origin (the corner of the "L":
    with tau rising, the norm falls first, then the residual rises). End points and points
    where the curve stands still (speed below 1e-3 of its largest, e.g. the flat start of a
    sweep at tiny tau, where the curvature is rounding noise) are NaN. Written here because
    no maintained library in the environment implements the L-curve corner; it is a few
    lines of calculus.
    """
    t = np.log10(np.asarray(tau, float))
    rho = np.log10(np.maximum(np.asarray(residual_norm, float), 1e-300))
    eta = np.log10(np.maximum(np.asarray(solution_norm, float), 1e-300))
    if not (t.shape == rho.shape == eta.shape) or t.size < 5:
        raise InputError(f"L-curve needs >= 5 points of equal length, got {t.size}, {rho.size} and {eta.size}")
    if np.any(np.diff(t) <= 0):
        raise InputError("L-curve: tau must be increasing")
    d_rho, d_eta = np.gradient(rho, t), np.gradient(eta, t)
    dd_rho, dd_eta = np.gradient(d_rho, t), np.gradient(d_eta, t)
    speed = np.hypot(d_rho, d_eta)
    with np.errstate(divide="ignore", invalid="ignore"):
        kappa = (d_rho * dd_eta - dd_rho * d_eta) / speed**3
    kappa[speed < 1e-3 * np.nanmax(speed)] = np.nan
    kappa[[0, -1]] = np.nan
    return kappa


def lcurve_corner(tau: Sequence[float], residual_norm: Sequence[float], solution_norm: Sequence[float]) -> int:
    """Index of the L-curve corner: the point of maximum curvature (Hansen), see
    :func:`lcurve_curvature`. A curve with no point of positive curvature has no corner: a
    warning is logged and the point of largest curvature is returned all the same."""
    kappa = lcurve_curvature(tau, residual_norm, solution_norm)
    if not np.isfinite(kappa).any():
        log.warning("L-curve is flat: no curvature anywhere; returning the middle point")
        return int(len(kappa) // 2)
    best = int(np.nanargmax(kappa))
    if kappa[best] <= 0:
        log.warning("L-curve has no corner (no point of positive curvature); returning index %d", best)
    return best


# ---- two damage states at once -------------------------------------------------------------
@dataclass(frozen=True)
class TwoState:
    """Transform of two states' problems into one: x = [x_state1 (k), x_state2 (k)].

    ``evaluate(X, runner)`` returns objective Pi_1 + Pi_2, residuals [r_1, r_2] (their sum
    of squares is Pi_1 + Pi_2) and objectives [Pi_1, Pi_2] (NSGA-II). A point fails if
    either state fails (its reason is the first state's failure). One point runs the
    model twice, so it counts as ``evaluations_per_point = 2`` model evaluations: a run's
    ``n_evaluations`` and budget are in model evaluations.
    """

    problem1: object
    problem2: object
    parameters: ParameterSet
    name: str = "two_state"
    evaluations_per_point = 2
    n_objectives = 2

    @property
    def problems(self) -> tuple:
        return (self.problem1, self.problem2)

    @property
    def k(self) -> int:
        return len(self.problem1.parameters)

    @property
    def n_params(self) -> int:
        return 2 * self.k

    @property
    def x_initial(self) -> np.ndarray:
        return self.parameters.x_initial

    def theta(self, x: np.ndarray) -> np.ndarray:
        return self.parameters.to_physical(x)

    def evaluate(self, X: np.ndarray, runner=None) -> Evaluations:
        X = as_points(X, self.n_params)
        e1 = self.problem1.evaluate(X[:, : self.k], runner)
        e2 = self.problem2.evaluate(X[:, self.k :], runner)
        ok = e1.ok & e2.ok
        reasons = [r1 if r1 is not None else r2 for r1, r2 in zip(e1.reasons, e2.reasons)]
        details = [
            "; ".join(f"state {j + 1}: {d}" for j, d in enumerate(pair) if d) for pair in zip(e1.details, e2.details)
        ]
        return Evaluations(
            objective=e1.objective + e2.objective,
            residuals=np.concatenate([e1.residuals, e2.residuals], axis=1),
            objectives=np.column_stack([e1.objective, e2.objective]),
            ok=ok,
            reasons=reasons,
            details=details,
            correlations=list(zip(e1.correlations, e2.correlations)),
        )


def two_state(problem1, problem2, prefixes: tuple[str, str] = ("s1_", "s2_")) -> TwoState:
    """The two-state problem of two states' problems with equally many parameters."""
    if len(problem1.parameters) != len(problem2.parameters):
        raise InputError(
            f"the two states must have the same number of parameters, got "
            f"{len(problem1.parameters)} and {len(problem2.parameters)}"
        )
    parameters = ParameterSet(
        Parameter(prefix + p.name, p.initial, p.lower, p.upper, p.unit, p.description)
        for prefix, prob in zip(prefixes, (problem1, problem2))
        for p in prob.parameters
    )
    return TwoState(problem1, problem2, parameters)


# ---- local refinement ---------------------------------------------------------------------
def polish(problem, x0: np.ndarray, max_evaluations: int = 3000, diff_step: float = 1e-6, runner=None):
    """Refine x0 by the sensitivity method started there: ``run_optimizer("sm", x0=x0)``.

    The hybrid step after a global search (like MATLAB's ``HybridFcn``): trust-region least
    squares on the residuals within [0, 1]^k, tolerances 1e-12, every model evaluation
    (Jacobian included) counted and limited to ``max_evaluations``; only least-squares'
    own tolerances stop it (no stall or target rule). Returns the OptimizerResult, whose
    ``x_best`` is the best successful point evaluated, so never worse than x0 (evaluated first).
    """
    from framework.optimizers import Budget, run_optimizer

    x0 = np.clip(np.asarray(x0, dtype=float), 0.0, 1.0)
    budget = Budget(max_evaluations=max_evaluations, target_objective=None, stall_tolerance=0.0)
    return run_optimizer(
        "sm", problem, 0, budget, runner=runner, x0=x0.tolist(), diff_step=diff_step, ftol=1e-12, xtol=1e-12, gtol=1e-12
    )
