"""Sensitivity method (SM): iterated linearization solved with scipy.optimize.least_squares.

The classical SM linearizes R_e = R_a + S (P_u - P_0) with the sensitivity matrix S from
forward differences (n + 1 model runs per iteration) and updates P_u = P_0 + S^+ (R_e - R_a).
Here the same iteration is done by least_squares' trust-region reflective method on the
residual vector r(x) = [sqrt(alpha) eps_i, sqrt(beta)(1 - sqrt MAC_i)/sqrt MAC_i] with a
forward-difference Jacobian ("2-point", step ``diff_step`` relative) and bounds [0, 1] on
the normalized parameters, which keeps steps inside the physical box.

Jacobian (setting ``jacobian``): "exact" uses the problem's exact Jacobian from modal
derivatives (:meth:`framework.problem.UpdatingProblem.jacobian`; an error if the model or
the formulation has none), "fd" least_squares' forward differences, "auto" (default) the
exact one when available and cheaper by count than forward differences (its cost bound in
eigen-solve equivalents below the k model evaluations of a difference Jacobian), else
"fd". With "fd" the run is the one of earlier versions. An exact Jacobian falls back to
forward differences (step ``diff_step``) at points with repeated or close eigenvalues.

Reported: iterations (Jacobian evaluations, also when the budget ran out; also counted as
``n_jacobians``), every model evaluation including those of
the Jacobian (counted by the run's evaluator; an exact Jacobian in eigen-solve
equivalents), the Jacobian method and its counts in ``extra``, and the condition number of the
sensitivity matrix J = dr/dx at the solution (normalized coordinates). The shared
termination rule is applied after every trust-region iteration (least_squares' callback,
Pi = 2 cost), next to least_squares' own tolerances; the evaluation budget is enforced by
the evaluator.

Status: "converged" (least squares' tolerances), "target", "stalled", "max_iterations",
"budget", or "not_converged" (least squares gave up, or its last iterate is a failed
evaluation); "failed" is left to runs without any successful evaluation.

Starts: "initial" (the initial model), "random" (uniform in the box from the run's
generator), ``start_factor`` times the initial values (e.g. 0.92, 1.11), or an explicit
normalized point ``x0`` (e.g. to polish the result of a global search).
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import Field, field_validator

from framework.optimizers.base import Budget, BudgetExhausted, Outcome, Settings, Termination


class SMSettings(Settings):
    start: Literal["initial", "random"] = "initial"
    start_factor: float | None = Field(None, gt=0)
    x0: list[float] | None = None  # explicit start in normalized coordinates (e.g. to polish a GA/PSO result)
    diff_step: float = Field(1e-3, gt=0)
    ftol: float = Field(1e-10, gt=0)
    xtol: float = Field(1e-10, gt=0)
    gtol: float = Field(1e-10, gt=0)
    jacobian: Literal["auto", "exact", "fd"] = "auto"

    @field_validator("x0", mode="before")
    @classmethod
    def _array_to_list(cls, value):
        return value.tolist() if isinstance(value, np.ndarray) else value


def start_point(problem, seed: int, s: SMSettings) -> np.ndarray:
    """The start in normalized coordinates; ``problem`` is anything with parameters and n_params."""
    if s.x0 is not None:
        x0 = np.asarray(s.x0, dtype=float)
        if x0.shape != (problem.n_params,) or not np.all(np.isfinite(x0)):
            raise ValueError(f"sm: x0 must be {problem.n_params} finite numbers in [0, 1], got {s.x0!r}")
        return np.clip(x0, 0.0, 1.0)
    if s.start_factor is not None:
        theta0 = problem.parameters.initial * s.start_factor
        return np.clip(problem.parameters.to_normalized(theta0), 0.0, 1.0)
    if s.start == "random":
        return np.random.default_rng(seed).random(problem.n_params)
    return problem.x_initial.copy()


def exact_jacobian_available(evaluator) -> bool:
    """True when the run's problem offers an exact Jacobian (model derivatives and formulation)."""
    return bool(getattr(evaluator.problem, "has_exact_jacobian", False)) and evaluator.cost == 1


def jacobian_method(evaluator, choice: str) -> str:
    """The Jacobian used for setting ``choice`` ("auto", "exact", "fd"): "exact" or "fd"."""
    available = exact_jacobian_available(evaluator)
    if choice == "exact" and not available:
        raise ValueError(
            "sm: jacobian 'exact' needs a model with modal_derivatives and a formulation with an exact "
            "Jacobian (spec or reference); use jacobian 'auto' or 'fd'"
        )
    if choice == "fd" or not available:
        return "fd"
    if choice == "auto" and evaluator.problem.jacobian_cost_bound >= evaluator.n_params:
        return "fd"
    return "exact"


def jacobian_argument(evaluator, method: str, diff_step: float):
    """least_squares' ``jac``: the evaluator's counted Jacobian for "exact", "2-point" for "fd".

    Also usable by other iterations of the method: ``evaluator.jacobian(x, fd_step)`` gives dr/dx."""
    if method == "fd":
        return "2-point"
    return lambda x: evaluator.jacobian(x, fd_step=diff_step)


def run(evaluator, seed: int, budget: Budget, **settings) -> Outcome:
    from scipy.optimize import least_squares

    s = SMSettings(**settings)
    x0 = start_point(evaluator, seed, s)
    termination = Termination(budget, evaluator)

    def callback(intermediate_result):
        # Pi of the current iterate (2 x cost), unless that point failed
        value = 2.0 * float(intermediate_result.cost)
        if evaluator.is_failed(intermediate_result.x):
            value = evaluator.best_objective
        if termination.update(value):
            raise StopIteration

    extra: dict = {"x_start": x0.tolist(), "theta_start": evaluator.parameters.to_physical(x0).tolist()}
    method = jacobian_method(evaluator, s.jacobian)
    extra["jacobian"] = method
    try:
        res = least_squares(
            evaluator.residuals,
            x0,
            jac=jacobian_argument(evaluator, method, s.diff_step),
            bounds=(0.0, 1.0),
            method="trf",
            diff_step=s.diff_step,
            ftol=s.ftol,
            xtol=s.xtol,
            gtol=s.gtol,
            max_nfev=budget.max_evaluations,
            callback=callback,
        )
        if termination.reason is not None:
            status = termination.reason
        elif res.status <= 0 or evaluator.is_failed(res.x):
            status = "not_converged"  # least squares gave up, or stopped on a failed point
        else:
            status = "converged"
        n_iter = int(res.njev)
        if method == "fd":  # least_squares differenced by itself: its Jacobians are counted here
            evaluator.n_jacobians += n_iter
        message = str(res.message)
        J = np.asarray(res.jac)
        extra["condition_number"] = float(np.linalg.cond(J)) if J.size else float("nan")
        extra["singular_values"] = np.linalg.svd(J, compute_uv=False).tolist() if J.size else []
        if status == "converged" and budget.target_objective is not None and 2 * res.cost < budget.target_objective:
            status = "target"
    except BudgetExhausted:
        # iterations = Jacobians computed (least_squares' njev: 1 + accepted steps)
        n_iter = evaluator.n_jacobians if method == "exact" else termination.iterations + 1
        if method == "fd":
            evaluator.n_jacobians += n_iter
        status, message = "budget", "evaluation budget exhausted"
    if method == "exact":
        extra["jacobian_methods"] = dict(evaluator.jacobian_methods)
        extra["jacobian_equivalents"] = evaluator.jacobian_equivalents
    return Outcome(status, n_iter, message=message, extra=extra)
