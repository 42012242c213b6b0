"""Maximum-likelihood calibration of a model's parameters (multi-start least squares).

Minimizes chi2(theta) = sum r(theta)^2 of the ``gaussian`` formulation
(:mod:`framework.updating.formulations.gaussian`, residuals whitened by the data's noise) over the
box of the parameters with the framework's sensitivity method (``run_optimizer("sm")``,
scipy least_squares trust-region on the whitened residual vector) from the initial point
and ``n_starts - 1`` random starts (seeded), keeping the best. The least-squares minimum
is the maximum-likelihood estimate because the noise is Gaussian with known sigmas.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from framework.core.errors import ModelEvaluationError
from framework.core.parameters import ParameterSet
from framework.measured.modes import MeasuredModes
from framework.models.base import ModalResult, StructuralModel
from framework.optimizers import Budget, run_optimizer
from framework.updating.formulations import gaussian
from framework.updating.objectives import ObjectiveSpec
from framework.updating.pairing import ModeCorrelation
from framework.updating.problem import UpdatingProblem

log = logging.getLogger(__name__)


def gaussian_spec(
    mac_threshold: float = 0.5,
    frequency_window: float | None = None,
    unmatched_window: float = gaussian.DEFAULT_UNMATCHED_WINDOW,
    use_shapes: bool = True,
) -> ObjectiveSpec:
    """ObjectiveSpec selecting the Gaussian formulation; Pi = chi2 (failures cost 1e12)."""
    return ObjectiveSpec(
        formulation="gaussian",
        mac_threshold=mac_threshold,
        frequency_window=frequency_window,
        use_shapes=use_shapes,
        failure_penalty=1e12,
        options={"unmatched_window": unmatched_window},
    )


@dataclass
class Fit:
    """Calibrated model: parameters, theta (physical), chi2, residuals, correlation, modes."""

    label: str
    active: dict[str, str]
    parameters: ParameterSet
    theta: np.ndarray
    chi2: float
    residuals: np.ndarray
    correlation: ModeCorrelation
    modal: ModalResult
    n_data: int
    n_evaluations: int
    start_chi2: list[float] = field(default_factory=list)

    @property
    def k(self) -> int:
        return len(self.parameters)

    @property
    def n_unmatched(self) -> int:
        return int(np.sum(~self.correlation.matched))

    def gap(self) -> dict[str, float]:
        """Max |frequency error| (%) and min MAC over matched modes, number unmatched."""
        c = self.correlation
        m = c.matched
        err = np.abs(c.frequency_error[m]) * 100.0 if m.any() else np.array([np.nan])
        mac = c.mac[m] if m.any() else np.array([np.nan])
        return {
            "max_freq_error_pct": float(np.nanmax(err)) if err.size else float("nan"),
            "min_mac": float(np.nanmin(mac)) if np.isfinite(mac).any() else float("nan"),
            "n_unmatched": self.n_unmatched,
        }


def calibrate(
    model: StructuralModel,
    measured: MeasuredModes,
    *,
    parameters: ParameterSet | None = None,
    spec: ObjectiveSpec | None = None,
    n_starts: int = 3,
    seed: int = 0,
    max_evaluations: int = 400,
    label: str = "",
    active: dict[str, str] | None = None,
    x_starts: list[np.ndarray] | None = None,
) -> Fit:
    """Best of ``n_starts`` least-squares runs.

    Starts: the points ``x_starts`` (normalized; default: the parameters' initial
    values), then random points of the run's seeded generator up to ``n_starts``.
    """
    spec = spec or gaussian_spec()
    problem = UpdatingProblem(model, measured, parameters, spec, name=label)
    params = problem.parameters
    budget = Budget(max_evaluations=max_evaluations, target_objective=None, stall_iterations=10)
    fixed = list(x_starts) if x_starts is not None else [params.x_initial]
    best = None
    starts: list[float] = []
    n_eval = 0
    tolerances = {"ftol": 1e-8, "xtol": 1e-8, "gtol": 1e-8}
    for i in range(max(n_starts, len(fixed))):
        if i < len(fixed):
            x0 = np.clip(np.asarray(fixed[i], float), 0.0, 1.0)
            res = run_optimizer("sm", problem, seed + i, budget, x0=x0.tolist(), **tolerances)
        else:
            res = run_optimizer("sm", problem, seed + i, budget, start="random", **tolerances)
        n_eval += res.n_evaluations
        starts.append(float(res.objective))
        if res.status != "failed" and (best is None or res.objective < best.objective):
            best = res
    if best is None:
        raise ModelEvaluationError("calibration_failed", f"{label}: every evaluation of every start failed")
    theta = best.theta_best
    ev = problem.evaluate(best.x_best[None, :])
    values = problem.parameters.as_dict(theta)
    modal = model.modal(values)
    fit = Fit(
        label=label,
        active=dict(active or {}),
        parameters=params,
        theta=theta,
        chi2=float(ev.objective[0]),
        residuals=ev.residuals[0],
        correlation=ev.correlations[0],
        modal=modal,
        n_data=gaussian.n_data(measured, spec),
        n_evaluations=n_eval,
        start_chi2=starts,
    )
    log.info("calibrated %s: chi2 %.4g (starts %s), %d evaluations", label, fit.chi2, starts, n_eval)
    return fit
