"""Quasi-random screening: evaluate a space-filling sample of the box in one population call.

The global phase of a hybrid (:mod:`framework.optimizers.hybrid`) that makes no assumption
about the objective: ``n_points`` points (default: every evaluation the phase may spend)
from :func:`framework.optimizers.sampling.sample` (Sobol' by default), seeded from the run's
seed, optionally with the initial model as the first point. The points are evaluated in one
call (vectorized models solve them at once; the process and Dask runners spread them).
"""

from __future__ import annotations

from pydantic import Field

from framework.core.status import Status
from framework.optimizers.base import Budget, Optimizer, Outcome, Settings
from framework.optimizers.sampling import Sampler, sample


class ScreeningSettings(Settings):
    sampler: Sampler = "sobol"
    n_points: int | None = Field(None, gt=0)
    include_initial: bool = False


def run(evaluator, seed: int, budget: Budget, s: ScreeningSettings) -> Outcome:
    affordable = int(min(budget.max_evaluations, evaluator.remaining) // evaluator.cost)
    n = min(s.n_points or affordable, affordable)
    if n < 1:
        return Outcome(Status.BUDGET, 0, message="no evaluation left for the screening sample")
    X = sample(n, evaluator.n_params, seed, s.sampler)
    if s.include_initial:
        X[0] = evaluator.x_initial
    evaluator.objective(X)
    status = Status.COMPLETED if n == (s.n_points or n) else Status.BUDGET
    return Outcome(status, 1, extra={"sampler": s.sampler, "n_points": int(n)})


OPTIMIZER = Optimizer("screening", ScreeningSettings, run)
