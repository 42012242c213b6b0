"""Genetic algorithm on pymoo (real-coded, in normalized coordinates).

Source settings (SPEC 4): population 20, tournament selection, two-point crossover with
crossover fraction 0.7, mutation rate 0.01, elitism. Mapping to pymoo:

- selection "tournament": pymoo TournamentSelection (binary, by fitness);
  "roulette": fitness-proportional selection with rank scaling, expectation ~ 1/sqrt(rank)
  (the default scaling of the GA the source used; pymoo has no roulette operator, so it is
  written here);
- crossover "single_point" / "two_point" / "scattered" (uniform): pymoo point / uniform
  crossover, applied to a mating with probability ``crossover_fraction``;
- mutation: each gene is reset to a uniform random value in its bounds with probability
  ``mutation_rate`` (uniform mutation; pymoo has none for real variables, so it is written
  here);
- elitism: pymoo's GA survival keeps the best ``pop_size`` of parents and offspring.

The run's generator is pymoo's own ``default_rng(seed)``.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import Field

from framework.optimizers.base import Budget, Outcome, Settings, Termination
from framework.optimizers.pymoo_problem import pymoo_problem


class GASettings(Settings):
    pop_size: int = Field(20, ge=4)
    selection: Literal["tournament", "roulette"] = "tournament"
    crossover: Literal["single_point", "two_point", "scattered"] = "two_point"
    crossover_fraction: float = Field(0.7, ge=0, le=1)
    mutation_rate: float = Field(0.01, ge=0, le=1)


def _operators(s: GASettings):
    from pymoo.core.mutation import Mutation
    from pymoo.core.selection import Selection
    from pymoo.operators.crossover.pntx import SinglePointCrossover, TwoPointCrossover
    from pymoo.operators.crossover.ux import UniformCrossover

    class UniformResetMutation(Mutation):
        """Each gene replaced by U(xl, xu) with probability prob_var."""

        def _do(self, problem, X, *args, random_state=None, **kwargs):
            X = np.array(X, dtype=float, copy=True)
            mask = random_state.random(X.shape) < self.rate
            X[mask] = (problem.xl + random_state.random(X.shape) * (problem.xu - problem.xl))[mask]
            return X

    class RankRouletteSelection(Selection):
        """Fitness-proportional selection on rank-scaled fitness 1/sqrt(rank)."""

        def _do(self, problem, pop, n_select, n_parents, random_state=None, **kwargs):
            F = pop.get("F")[:, 0]
            rank = np.empty(len(F))
            rank[np.argsort(F, kind="stable")] = np.arange(1, len(F) + 1)
            p = 1.0 / np.sqrt(rank)
            p /= p.sum()
            return random_state.choice(len(F), size=(n_select, n_parents), p=p)

    mutation = UniformResetMutation(prob=1.0)
    mutation.rate = s.mutation_rate
    crossover_cls = {
        "single_point": SinglePointCrossover,
        "two_point": TwoPointCrossover,
        "scattered": UniformCrossover,
    }[s.crossover]
    crossover = crossover_cls(prob=s.crossover_fraction)
    if s.selection == "roulette":
        selection = RankRouletteSelection()
    else:
        from pymoo.algorithms.soo.nonconvex.ga import comp_by_cv_and_fitness
        from pymoo.operators.selection.tournament import TournamentSelection

        selection = TournamentSelection(func_comp=comp_by_cv_and_fitness)
    return selection, crossover, mutation


def run(evaluator, seed: int, budget: Budget, **settings) -> Outcome:
    from pymoo.algorithms.soo.nonconvex.ga import GA
    from pymoo.operators.sampling.rnd import FloatRandomSampling
    from pymoo.termination.max_gen import MaximumGenerationTermination

    s = GASettings(**settings)
    selection, crossover, mutation = _operators(s)
    algorithm = GA(
        pop_size=s.pop_size,
        sampling=FloatRandomSampling(),
        selection=selection,
        crossover=crossover,
        mutation=mutation,
        eliminate_duplicates=True,
    )
    termination = Termination(budget, evaluator)
    algorithm.setup(
        pymoo_problem(evaluator), termination=MaximumGenerationTermination(10**9), seed=seed, verbose=False
    )
    generation = 0
    while termination.affords(s.pop_size):
        algorithm.next()
        generation += 1
        # best so far over successful evaluations (= the elitist population's best without failures)
        if termination.update(evaluator.best_objective):
            break
    return Outcome(
        termination.status,
        generation,
        extra={"pop_size": s.pop_size, "selection": s.selection, "crossover": s.crossover},
    )
