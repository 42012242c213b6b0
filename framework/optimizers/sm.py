"""Sensitivity method (SM): iterated linearization solved with scipy.optimize.least_squares.

The classical SM linearizes R_e = R_a + S (P_u - P_0) with the sensitivity matrix S from
forward differences (n + 1 model runs per iteration) and updates P_u = P_0 + S^+ (R_e - R_a).
Here the same iteration is done by least_squares' trust-region reflective method on the
residual vector r(x) = [sqrt(alpha) eps_i, sqrt(beta)(1 - sqrt MAC_i)/sqrt MAC_i] with a
forward-difference Jacobian ("2-point", step ``diff_step`` relative) and bounds [0, 1] on
the normalized parameters, which keeps steps inside the physical box.

Jacobian (setting ``jacobian``): "exact" uses the problem's exact Jacobian from modal
derivatives (:meth:`framework.updating.problem.UpdatingProblem.jacobian`; an error if the model or
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

``method``: "trust_region" (default, above: ours) or "pseudo_inverse", the source's
iteration (SPEC 4; :func:`run_pseudo_inverse`): per iteration the residual at P_k and S by
one-sided differences (n + 1 model runs, evaluated as one batch), then the full step
P_k+1 = P_k - S^+ r(P_k) (r = R_a - R_e), with no trust region, step control or line
search ("unbounded within each step"). The problem evaluates only inside the updating
bounds, so the new point is projected onto them (clipped, normalized [0, 1]) after the step.
Converged when the projected step is below ``step_tolerance`` in every normalized
coordinate; the shared termination rule and the budget apply per iteration.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import Field, field_validator

from framework.core.status import Status
from framework.optimizers.base import Budget, BudgetExhausted, Optimizer, Outcome, Settings, Termination


class SMSettings(Settings):
    method: Literal["trust_region", "pseudo_inverse"] = "trust_region"
    start: Literal["initial", "random"] = "initial"
    start_factor: float | None = Field(None, gt=0)
    x0: list[float] | None = None  # explicit start in normalized coordinates (e.g. to polish a GA/PSO result)
    diff_step: float = Field(1e-3, gt=0)
    ftol: float = Field(1e-10, gt=0)
    xtol: float = Field(1e-10, gt=0)
    gtol: float = Field(1e-10, gt=0)
    jacobian: Literal["auto", "exact", "fd"] = "auto"
    # least_squares' variable scaling: "unit" (default) or "jac" (ours: scaled by the Jacobian's
    # column norms, faster along the footbridge's flat valleys with parameters on their bounds)
    x_scale: Literal["unit", "jac"] = "unit"
    # pseudo-inverse iteration only: convergence on the projected step (normalized), pinv cut-off
    step_tolerance: float = Field(1e-6, gt=0)
    pinv_rcond: float = Field(1e-12, gt=0, lt=1)

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


def run(evaluator, seed: int, budget: Budget, s: SMSettings) -> Outcome:
    from scipy.optimize import least_squares

    if s.method == "pseudo_inverse":
        return run_pseudo_inverse(evaluator, seed, budget, s)
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
            x_scale=1.0 if s.x_scale == "unit" else "jac",
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
            status = Status.NOT_CONVERGED  # least squares gave up, or stopped on a failed point
        else:
            status = Status.CONVERGED
        n_iter = int(res.njev)
        if method == "fd":  # least_squares differenced by itself: its Jacobians are counted here
            evaluator.count_jacobians("fd", n_iter)
        message = str(res.message)
        J = np.asarray(res.jac)
        extra["condition_number"] = float(np.linalg.cond(J)) if J.size else float("nan")
        extra["singular_values"] = np.linalg.svd(J, compute_uv=False).tolist() if J.size else []
        if (status == Status.CONVERGED and budget.target_objective is not None
                and 2 * res.cost < budget.target_objective):
            status = Status.TARGET
    except BudgetExhausted:
        # iterations = Jacobians computed (least_squares' njev: 1 + accepted steps)
        n_iter = evaluator.n_jacobians if method == "exact" else termination.iterations + 1
        if method == "fd":
            evaluator.count_jacobians("fd", n_iter)
        status, message = Status.BUDGET, "evaluation budget exhausted"
    if method == "exact":
        extra["jacobian_methods"] = dict(evaluator.jacobian_methods)
        extra["jacobian_equivalents"] = evaluator.jacobian_equivalents
    return Outcome(status, n_iter, message=message, extra=extra)


# ---- the source's pseudo-inverse iteration -------------------------------------------------
def difference_points(x: np.ndarray, step: float) -> tuple[np.ndarray, np.ndarray]:
    """The n + 1 points of a one-sided difference Jacobian at x in [0, 1]^n and the signed
    steps: x + h e_j, or x - h e_j where x + h e_j would leave the box."""
    h = np.where(x + step <= 1.0, step, -step)
    return np.vstack([x, x + np.diag(h)]), h


def pseudo_inverse_step(jac: np.ndarray, r: np.ndarray, rcond: float) -> np.ndarray:
    """Gauss-Newton step of the linearized residual r + J dx = 0: dx = -J^+ r (minimum norm)."""
    return -np.linalg.pinv(jac, rcond=rcond) @ r


def run_pseudo_inverse(evaluator, seed: int, budget: Budget, s: SMSettings) -> Outcome:
    """P_k+1 = clip(P_k - S^+ r(P_k)) until the projected step is below ``s.step_tolerance``.

    Each iteration evaluates P_k and its n difference points in one batch (n + 1 model
    runs). Stops as "converged", by the shared termination rule, on the budget, or
    "not_converged" when P_k or a difference point fails. The final point is the last
    evaluated iterate (the method's answer; with a parameter held on a bound it is a fixed
    point of the projected iteration, which need not be the best point visited). extra:
    start, per iteration Pi, step norm and the parameters clipped by the projection, the
    best iterate, condition number and singular values of the last S.
    """
    x = start_point(evaluator, seed, s)
    termination = Termination(budget, evaluator)
    n = evaluator.n_params
    extra: dict = {"x_start": x.tolist(), "theta_start": evaluator.parameters.to_physical(x).tolist(),
                   "iterations": []}
    last_x, last_pi, best_pi = None, np.inf, np.inf
    status, message, jac = Status.BUDGET, "evaluation budget exhausted", None
    iteration = 0
    while evaluator.affords(n + 1):
        points, h = difference_points(x, s.diff_step)
        ev = evaluator.evaluate(points)
        iteration += 1
        if not np.all(ev.ok):
            failed = "the iterate" if not ev.ok[0] else "a difference point"
            reason = ev.reasons[int(np.argmin(ev.ok))]
            status, message = Status.NOT_CONVERGED, f"{failed} failed at iteration {iteration}: {reason}"
            break
        r = ev.residuals[0]
        pi = float(ev.objective[0])
        last_x, last_pi = x.copy(), pi
        if pi < best_pi:
            best_pi = pi
            extra["best_iterate"] = {"iteration": iteration, "objective": pi, "x": x.tolist()}
        jac = (ev.residuals[1:] - r).T / h
        unclipped = x + pseudo_inverse_step(jac, r, s.pinv_rcond)
        x_new = np.clip(unclipped, 0.0, 1.0)
        step = x_new - x
        clipped = [evaluator.parameters.names[j] for j in np.flatnonzero(x_new != unclipped)]
        extra["iterations"].append({"iteration": iteration, "objective": pi, "max_step": float(np.abs(step).max()),
                                    "clipped": clipped})
        if np.abs(step).max() < s.step_tolerance:
            status = Status.CONVERGED
            message = f"projected step below {s.step_tolerance:g} after {iteration} iterations"
            break
        if termination.update(pi):
            status, message = termination.reason, f"termination rule: {termination.reason}"
            break
        x = x_new
    if jac is not None and np.all(np.isfinite(jac)):
        sv = np.linalg.svd(jac, compute_uv=False)
        extra["condition_number"] = float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
        extra["singular_values"] = sv.tolist()
    extra["final_clipped"] = extra["iterations"][-1]["clipped"] if extra["iterations"] else []
    if status == Status.CONVERGED and budget.target_objective is not None and last_pi < budget.target_objective:
        status = Status.TARGET
    return Outcome(status, iteration, message=message, extra=extra, x_best=last_x,
                   objective=last_pi if last_x is not None else None)


OPTIMIZER = Optimizer("sm", SMSettings, run)
