"""NSGA-II on pymoo (SPEC 4, damage study): several objectives ``problem.objectives(X)``.

Mapping of the source's settings (MATLAB ``gamultiobj`` style) onto pymoo's NSGA2:

- population ``pop_size`` (500), ``n_generations`` (200): pymoo evaluates the initial
  population in generation 1 and ``pop_size`` offspring in each later generation, so a
  run costs pop_size x n_generations points; fewer generations are run when
  ``budget.max_evaluations`` is smaller (status "budget").
- termination: the shared rule (:class:`~framework.optimizers.base.Termination`) after
  every generation, on the best scalar objective Pi evaluated so far (the smallest sum of
  the objectives Pi_f + Pi_MAC, or Pi_1 + Pi_2 for two damage states, plus penalty terms):
  "stalled" when it improved by less than ``stall_tolerance`` over ``stall_iterations``
  generations, "target" below ``target_objective``, "max_iterations" after
  ``max_iterations`` generations; "max_generations" when all generations ran.
- crossover probability 0.8: simulated binary crossover ``SBX(prob=0.8)`` (probability
  that a mating pair is recombined; pymoo's default eta = 15).
- mutation 0.01: polynomial mutation applied to every offspring, each variable mutated
  with probability 0.01 (``PM(prob=1, prob_var=0.01)``), i.e. the source's per-gene rate.
- "keep 35 % of the population in the first front" (``first_front_fraction``): pymoo's
  rank-and-crowding survival has no such knob - it fills the next population front by
  front and would let the first front take the whole population. :class:`ParetoFractionSurvival`
  subclasses it: at most ceil(fraction x pop_size) members of the first front survive
  (those with the largest crowding distance), the remaining places go to later fronts in
  rank and crowding order (diversity), and first-front members fill any places left when
  the later fronts run out. ``first_front_fraction=1`` gives plain NSGA-II.
- final solution: the Pareto point nearest the ideal point in objectives normalized by
  (F - ideal) / (nadir - ideal) over the final front (ideal = minimum, nadir = maximum of
  each objective on the front); Euclidean distance.

``result.extra`` holds ``pareto_F`` (n_front, n_obj), ``pareto_X`` (normalized x),
``ideal_F``, ``nadir_F``, ``chosen_index``, ``chosen_F``, ``generations_run`` and the
settings used (plain lists and numbers); ``result.objective`` is the sum of the chosen
point's objectives. Failed points (whatever their penalty) are removed from the front
before the choice.
"""

from __future__ import annotations

import logging
import math

import numpy as np
from pydantic import Field

from framework.core.status import Status
from framework.optimizers.base import Budget, Optimizer, Outcome, Settings, Termination
from framework.optimizers.pymoo_problem import pymoo_problem

log = logging.getLogger(__name__)


class NSGA2Settings(Settings):
    pop_size: int = Field(500, ge=4)
    n_generations: int = Field(200, ge=1)
    crossover_prob: float = Field(0.8, ge=0, le=1)
    mutation_prob: float = Field(0.01, ge=0, le=1)
    first_front_fraction: float = Field(0.35, gt=0, le=1)
    crossover_eta: float = Field(15.0, gt=0)
    mutation_eta: float = Field(20.0, gt=0)


def nearest_to_ideal(F: np.ndarray) -> int:
    """Index of the row of F nearest the ideal point after normalizing each objective to [0, 1]."""
    F = np.atleast_2d(np.asarray(F, dtype=float))
    ideal, nadir = F.min(axis=0), F.max(axis=0)
    span = np.where(nadir > ideal, nadir - ideal, 1.0)
    return int(np.argmin(np.linalg.norm((F - ideal) / span, axis=1)))


def _survival_class():
    """ParetoFractionSurvival, built lazily so that importing this module does not import pymoo."""
    from pymoo.operators.survival.rank_and_crowding import RankAndCrowding

    class ParetoFractionSurvival(RankAndCrowding):
        """Rank-and-crowding survival with at most ``fraction`` of the survivors from the first front."""

        def __init__(self, fraction: float):
            super().__init__()
            self.fraction = fraction

        def _do(self, problem, pop, *args, random_state=None, n_survive=None, **kwargs):
            F = pop.get("F").astype(float, copy=False)
            fronts = self.nds.do(F)
            cap = max(1, math.ceil(self.fraction * n_survive))
            order: list[int] = []
            deferred: list[int] = []
            for rank, front in enumerate(fronts):
                crowding = self.crowding_func.do(F[front, :], n_remove=0)
                for j, i in enumerate(front):
                    pop[i].set("rank", rank)
                    pop[i].set("crowding", crowding[j])
                ranked = [int(i) for i in front[np.argsort(-crowding, kind="stable")]]
                if rank == 0 and len(ranked) > cap:
                    order.extend(ranked[:cap])
                    deferred.extend(ranked[cap:])
                else:
                    order.extend(ranked)
            order.extend(deferred)
            return pop[order[:n_survive]]

    return ParetoFractionSurvival


def run(evaluator, seed: int, budget: Budget, s: NSGA2Settings) -> Outcome:
    """NSGA-II on ``evaluator.objectives``; final point nearest the ideal point of the front."""
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.operators.crossover.sbx import SBX
    from pymoo.operators.mutation.pm import PM
    from pymoo.termination.max_gen import MaximumGenerationTermination

    n_gen = min(s.n_generations, max(1, budget.max_evaluations // (s.pop_size * evaluator.cost)))
    if n_gen < s.n_generations:
        log.info(
            "nsga2: budget of %d evaluations allows %d of %d generations",
            budget.max_evaluations,
            n_gen,
            s.n_generations,
        )
    algorithm = NSGA2(
        pop_size=s.pop_size,
        crossover=SBX(prob=s.crossover_prob, eta=s.crossover_eta),
        mutation=PM(prob=1.0, prob_var=s.mutation_prob, eta=s.mutation_eta),
        survival=_survival_class()(s.first_front_fraction),
        eliminate_duplicates=True,
    )
    termination = Termination(budget, evaluator)
    algorithm.setup(
        pymoo_problem(evaluator, n_obj=evaluator.n_objectives),
        termination=MaximumGenerationTermination(n_gen),
        seed=int(seed) % (2**32),
        verbose=False,
    )
    generation = 0
    while algorithm.has_next() and termination.affords(s.pop_size):
        algorithm.next()
        generation += 1
        if termination.update(evaluator.best_objective):
            break
    if generation == 0:  # the budget does not afford one population: nothing evaluated, a failed run
        return Outcome(Status.BUDGET, 0, message=f"budget of {budget.max_evaluations} evaluations is smaller than "
                                            f"one population of {s.pop_size}")
    res = algorithm.result()
    front_F = np.atleast_2d(np.asarray(res.F, dtype=float))
    front_X = np.atleast_2d(np.asarray(res.X, dtype=float))
    keep = np.array([not evaluator.is_failed(x) for x in front_X], dtype=bool)
    if keep.any():
        front_F, front_X = front_F[keep], front_X[keep]
    chosen = nearest_to_ideal(front_F)
    extra = {
        "pareto_F": front_F,
        "pareto_X": front_X,
        "ideal_F": front_F.min(axis=0),
        "nadir_F": front_F.max(axis=0),
        "chosen_index": chosen,
        "chosen_F": front_F[chosen],
        **s.model_dump(),
        "generations_run": generation,
    }
    if termination.reason is not None:
        status = termination.reason
    else:
        status = Status.MAX_GENERATIONS if generation >= s.n_generations else Status.BUDGET
    return Outcome(
        status, generation, message=f"{len(front_F)} points on the final front", extra=extra,
        x_best=front_X[chosen] if keep.any() else None, objective=float(front_F[chosen].sum()),
    )  # fmt: skip


OPTIMIZER = Optimizer("nsga2", NSGA2Settings, run)
