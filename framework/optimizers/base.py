"""What every optimizer adapter shares: budget, termination rule, result, seeding.

Every adapter has the signature ``run(problem, seed, budget, **settings) -> OptimizerResult``.
The problem is any object with ``n_params``, ``objective(X)`` (and ``residuals(x)`` for
least squares, ``objectives(X)`` for multi-objective methods), ``parameters`` and a ``log``
that counts evaluations (:class:`framework.problem.UpdatingProblem`).

Termination (SPEC 4, lab study): stop when the best value improved by less than
``stall_tolerance`` over ``stall_iterations`` successive iterations, or the best value is
below ``target_objective``, or ``max_evaluations`` model evaluations were spent.
"""

from __future__ import annotations

import contextlib
import time
from dataclasses import dataclass, field

import numpy as np
from pydantic import BaseModel, ConfigDict, Field


class Budget(BaseModel):
    """Evaluation budget and the termination rule shared by the optimizers."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    max_evaluations: int = Field(50_000, gt=0)
    stall_iterations: int = Field(10, gt=0)
    stall_tolerance: float = Field(1e-8, ge=0)
    target_objective: float | None = 1e-6
    max_iterations: int | None = Field(None, gt=0)


class Settings(BaseModel):
    """Base of every optimizer's settings: unknown keys are rejected."""

    model_config = ConfigDict(extra="forbid", frozen=True)


class BudgetExhausted(Exception):
    """Raised inside an objective wrapper when the evaluation budget is spent."""


@dataclass
class OptimizerResult:
    """Outcome of one optimizer run (x in [0, 1]^k, theta in physical units)."""

    algorithm: str
    seed: int
    x_best: np.ndarray
    theta_best: np.ndarray
    objective: float
    n_evaluations: int
    n_iterations: int
    wall_s: float
    status: str
    message: str = ""
    history: np.ndarray = field(default_factory=lambda: np.array([]))
    n_failed: int = 0
    failures: str = ""
    extra: dict = field(default_factory=dict)


class StallTracker:
    """Implements the termination rule on the sequence of best-so-far values per iteration."""

    def __init__(self, budget: Budget):
        self.budget = budget
        self.best = np.inf
        self.stalled = 0
        self.iterations = 0

    def update(self, best: float) -> str | None:
        """Record the best value after an iteration; return a stop reason or None."""
        self.iterations += 1
        improvement = self.best - best
        self.stalled = self.stalled + 1 if improvement < self.budget.stall_tolerance else 0
        self.best = min(self.best, best)
        if self.budget.target_objective is not None and self.best < self.budget.target_objective:
            return "target"
        if self.stalled >= self.budget.stall_iterations:
            return "stalled"
        if self.budget.max_iterations is not None and self.iterations >= self.budget.max_iterations:
            return "max_iterations"
        return None


def budget_left(problem, budget: Budget) -> int:
    return budget.max_evaluations - problem.log.n_evaluations


@contextlib.contextmanager
def seeded_global_numpy(seed: int):
    """Seed numpy's *global* generator for libraries that draw from it (pyswarms), then
    restore the previous state, so a run is reproducible from its seed and leaves no trace.
    Runs in one process are sequential; process and Dask workers each have their own state.
    """
    state = np.random.get_state()
    np.random.seed(seed % (2**32))
    try:
        yield
    finally:
        np.random.set_state(state)


class Timer:
    def __enter__(self):
        self.start = time.perf_counter()
        return self

    def __exit__(self, *exc):
        self.elapsed = time.perf_counter() - self.start
        return False


def make_result(
    algorithm: str,
    problem,
    seed: int,
    wall_s: float,
    status: str,
    n_iterations: int,
    message: str = "",
    extra: dict | None = None,
    x_best=None,
    objective=None,
) -> OptimizerResult:
    """Result from the problem's evaluation log (best point over every evaluation counted)."""
    log = problem.log
    if x_best is None:
        x_best = log.best_x if log.best_x is not None else problem.x_initial
        objective = log.best_objective
    x_best = np.clip(np.asarray(x_best, float), 0.0, 1.0)
    return OptimizerResult(
        algorithm=algorithm,
        seed=seed,
        x_best=x_best,
        theta_best=problem.parameters.to_physical(x_best),
        objective=float(objective),
        n_evaluations=log.n_evaluations,
        n_iterations=int(n_iterations),
        wall_s=float(wall_s),
        status=status,
        message=message,
        history=log.best_so_far(),
        n_failed=log.n_failed,
        failures=log.failure_summary(),
        extra=extra or {},
    )
