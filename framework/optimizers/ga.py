"""Genetic algorithm on pymoo (real-coded, in normalized coordinates).

Source settings (SPEC 4): population 20, tournament selection, two-point crossover with
crossover fraction 0.7, mutation rate 0.01, elitism. Mapping to pymoo:

- selection "tournament": pymoo TournamentSelection (binary, by fitness);
  "roulette": fitness-proportional selection with rank scaling, expectation ~ 1/sqrt(rank)
  (the default scaling of the GA the source used; pymoo has no roulette operator, so it is
  written here);
- crossover "single_point" / "two_point" / "scattered" (uniform): pymoo point / uniform
  crossover (of the two children of a mating the first is kept, as the toolbox makes one
  child per pair);
- mutation: each gene is reset to a uniform random value in its bounds with probability
  ``mutation_rate`` (uniform mutation; pymoo has none for real variables, so it is written
  here);
- ``scheme: toolbox`` (default, the meaning of the source's GA toolbox): each generation
  is ``elite_count`` elite children (the best parents, copied), then of the remaining
  n_r = pop_size - elite_count children round(crossover_fraction n_r) by crossover of two
  selected parents and the rest by mutation of one selected parent (crossover children are
  not mutated); the children replace the parents (generational). With pop_size 20,
  elite_count 2, fraction 0.7: 2 elite, 13 crossover, 5 mutation children, 18 evaluations
  per generation. Assumed toolbox defaults (our assumption, the source names none):
  ``elite_count`` = 2 (the toolbox's default before R2014; later ceil(0.05 pop_size) = 1),
  uniform mutation with the rate as per-gene probability, no duplicate elimination.
  pymoo has no such split, so the mating and the replacement are written here
  (:class:`FractionMating`, :class:`ElitistReplacement`) around pymoo's operators;
- ``scheme: pymoo`` (ours, the earlier behaviour): crossover applied to a mating with
  probability ``crossover_fraction``, every child mutated, duplicates eliminated, pymoo's
  survival keeps the best ``pop_size`` of parents and offspring.

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
    scheme: Literal["toolbox", "pymoo"] = "toolbox"
    elite_count: int = Field(2, ge=0)


def children_split(pop_size: int, elite_count: int, crossover_fraction: float) -> dict[str, int]:
    """Children per generation in the toolbox scheme: elite, then round(fraction n_r) by
    crossover of the remaining n_r = pop_size - elite, the rest by mutation."""
    elite = min(elite_count, pop_size)
    rest = pop_size - elite
    crossover = int(round(crossover_fraction * rest))
    return {"elite": elite, "crossover": crossover, "mutation": rest - crossover}


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
    mutation.uniform_reset = True
    mutation.rate = s.mutation_rate
    crossover_cls = {
        "single_point": SinglePointCrossover,
        "two_point": TwoPointCrossover,
        "scattered": UniformCrossover,
    }[s.crossover]
    crossover = crossover_cls(prob=s.crossover_fraction if s.scheme == "pymoo" else 1.0)
    if s.selection == "roulette":
        selection = RankRouletteSelection()
    else:
        from pymoo.algorithms.soo.nonconvex.ga import comp_by_cv_and_fitness
        from pymoo.operators.selection.tournament import TournamentSelection

        selection = TournamentSelection(func_comp=comp_by_cv_and_fitness)
    return selection, crossover, mutation


def _toolbox_parts(s: GASettings, selection, crossover, mutation):
    """The toolbox generation as a pymoo mating (children) and survival (replacement)."""
    from pymoo.core.infill import InfillCriterion
    from pymoo.core.population import Population
    from pymoo.core.survival import Survival

    split = children_split(s.pop_size, s.elite_count, s.crossover_fraction)

    class FractionMating(InfillCriterion):
        """n_crossover children from pairs (first child of each pair), n_mutation mutated
        copies of single parents; ``last_split`` records the counts of the last call."""

        last_split: dict[str, int] = {}

        def _do(self, problem, pop, n_offsprings, random_state=None, **kwargs):
            n_x = min(split["crossover"], n_offsprings)
            n_m = n_offsprings - n_x
            parts = []
            if n_x:
                pairs = selection(problem, pop, n_x, n_parents=2, random_state=random_state, **kwargs)
                kids = crossover(problem, pairs, random_state=random_state, **kwargs)
                parts.append(kids[:n_x])  # rows: first child of every pair, then the second ones
            if n_m:
                single = selection(problem, pop, n_m, n_parents=1, random_state=random_state, **kwargs)
                X = np.array([row[0].get("X") for row in single], dtype=float)
                parts.append(Population.new(X=mutation._do(problem, X, random_state=random_state)))
            self.last_split = {"elite": split["elite"], "crossover": n_x, "mutation": n_m}
            return Population.merge(*parts) if len(parts) > 1 else parts[0]

    class ElitistReplacement(Survival):
        """Next generation = the ``elite`` best parents + all children."""

        def __init__(self):
            super().__init__(filter_infeasible=False)

        def _do(self, problem, pop, *args, n_survive=None, algorithm=None, **kwargs):
            n_children = split["crossover"] + split["mutation"]
            if len(pop) <= n_survive or algorithm is None or algorithm.n_gen is None or len(pop) < n_children:
                return pop[np.argsort(pop.get("F")[:, 0], kind="stable")[:n_survive]]
            parents, children = pop[: len(pop) - n_children], pop[len(pop) - n_children:]
            elite = parents[np.argsort(parents.get("F")[:, 0], kind="stable")[: split["elite"]]]
            return Population.merge(elite, children)

    return FractionMating(), ElitistReplacement(), split


def run(evaluator, seed: int, budget: Budget, **settings) -> Outcome:
    from pymoo.algorithms.soo.nonconvex.ga import GA
    from pymoo.operators.sampling.rnd import FloatRandomSampling
    from pymoo.termination.max_gen import MaximumGenerationTermination

    s = GASettings(**settings)
    selection, crossover, mutation = _operators(s)
    if s.scheme == "toolbox":
        mating, survival, split = _toolbox_parts(s, selection, crossover, mutation)
        n_children = split["crossover"] + split["mutation"]
        algorithm = GA(
            pop_size=s.pop_size,
            sampling=FloatRandomSampling(),
            mating=mating,
            survival=survival,
            n_offsprings=n_children,
            eliminate_duplicates=False,
        )
    else:
        n_children = s.pop_size
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
    while termination.affords(max(n_children, 1) if generation else s.pop_size):
        algorithm.next()
        generation += 1
        # best so far over successful evaluations (= the elitist population's best without failures)
        if termination.update(evaluator.best_objective):
            break
    return Outcome(
        termination.status,
        generation,
        extra={"pop_size": s.pop_size, "selection": s.selection, "crossover": s.crossover,
               "scheme": s.scheme, "elite_count": s.elite_count if s.scheme == "toolbox" else None},
    )
