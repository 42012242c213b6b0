"""Simulated annealing with scipy.optimize.dual_annealing (generalized simulated annealing).

The source used classical SA: Boltzmann acceptance, exponential temperature decay
T_k = T0 0.95^k, initial temperature 200 and re-annealing every 200 iterations. scipy's
dual_annealing has other knobs; the mapping used here:

- ``initial_temp`` = the source's initial temperature (200). Its scale is the same
  objective-value scale; the visiting distribution differs (distorted Cauchy-Lorentz).
- re-anneal interval N -> ``restart_temp_ratio`` = T(N)/T0 with scipy's schedule
  T(t) = T0 (2^(qv-1) - 1) / ((1 + t)^(qv-1) - 1), so that re-annealing happens after
  N iterations as in the source (N = 200, qv = 2.62 gives 3.8e-4).
- schedule "exponential" (fast cooling) -> visit qv = 2.62 (scipy default);
  schedule "boltzmann" (slow, logarithmic cooling) -> visit qv = 1.5 (closer to classical
  SA: T decays like t^-(qv-1)). Acceptance: scipy's generalized Metropolis with
  ``accept`` (qa = -5, the closest allowed to Boltzmann's qa -> 1 limit is not available).
- ``local_search``: dual_annealing's L-BFGS-B polish of each new minimum (scipy default,
  on here: pure SA spends many more evaluations to reach 1e-4). Set false for pure SA: the
  source's SiA has no local search, so its replication studies (studies/lab_frame.yaml,
  selection_annealing.yaml, lab_frame_timing.yaml) set false, and the hybrid with local
  search is the variant labelled "annealing_local_search (ours)".

Termination: dual_annealing reports only each new best point (its callback), not its
iterations, so of the shared rule only the target applies (through the callback), plus
the evaluation budget (maxfun, and the run's evaluator) and ``max_iterations``
(scipy's maxiter: the smaller of the setting and ``budget.max_iterations``). The stall
rule needs the best value per iteration and is not applied.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import Field

from framework.core.status import Status
from framework.optimizers.base import Budget, BudgetExhausted, Optimizer, Outcome, Settings, Termination


class AnnealingSettings(Settings):
    initial_temp: float = Field(200.0, gt=0.01, le=5e4)
    reanneal_interval: int = Field(200, ge=1)
    schedule: Literal["exponential", "boltzmann"] = "exponential"
    visit: float | None = Field(None, gt=1.0, le=3.0)
    accept: float = Field(-5.0, le=-5.0, gt=-1e4)
    local_search: bool = True
    max_iterations: int = Field(1000, ge=1)


def restart_ratio(interval: int, qv: float) -> float:
    """T(N)/T0 of scipy's visiting temperature schedule after N iterations."""
    return (2.0 ** (qv - 1.0) - 1.0) / ((1.0 + interval) ** (qv - 1.0) - 1.0)


def run(evaluator, seed: int, budget: Budget, s: AnnealingSettings) -> Outcome:
    from scipy.optimize import dual_annealing

    qv = s.visit if s.visit is not None else (2.62 if s.schedule == "exponential" else 1.5)
    ratio = float(np.clip(restart_ratio(s.reanneal_interval, qv), 1e-12, 0.999))
    termination = Termination(budget, evaluator, rules=("target",))
    max_iterations = min(s.max_iterations, budget.max_iterations or s.max_iterations)

    def callback(x, f, context):  # a new best point; a failed one never meets the target
        return not evaluator.is_failed(x) and termination.update(f) is not None

    status, n_iter = Status.BUDGET, 0
    try:
        res = dual_annealing(
            evaluator.objective1,
            bounds=[(0.0, 1.0)] * evaluator.n_params,
            maxiter=max_iterations,
            initial_temp=s.initial_temp,
            restart_temp_ratio=ratio,
            visit=qv,
            accept=s.accept,
            maxfun=budget.max_evaluations,
            seed=np.random.default_rng(seed),
            no_local_search=not s.local_search,
            callback=callback,
        )
        n_iter = int(res.nit)
        status = termination.reason or Status.CONVERGED
        message = str(res.message)
    except BudgetExhausted:
        message = "evaluation budget exhausted"
    extra = {"visit": qv, "restart_temp_ratio": ratio, "initial_temp": s.initial_temp}
    return Outcome(status, n_iter, message=message, extra=extra)


OPTIMIZER = Optimizer("annealing", AnnealingSettings, run)
