"""Genetic algorithm on pymoo (real-coded, in normalized coordinates).

Source settings (SPEC 4): population 20, tournament selection, two-point crossover with
crossover fraction 0.7, mutation rate 0.01, elitism, in a MATLAB Global Optimization
Toolbox GA. Mapping to pymoo:

- selection "tournament": pymoo TournamentSelection (binary, by fitness; the toolbox's
  selectiontournament draws "Tournament size" players, 4 in the examples we found);
  "roulette": fitness-proportional selection with rank scaling, expectation ~ 1/sqrt(rank)
  (the default scaling of the GA the source used; pymoo has no roulette operator, so it is
  written here);
- crossover "single_point" / "two_point" / "scattered" (uniform): pymoo point / uniform
  crossover (of the two children of a mating the first is kept, as the toolbox makes one
  child per pair);
- ``scheme: toolbox`` (default, the meaning of the source's GA toolbox): each generation
  is ``elite_count`` elite children (the best parents, copied), then of the remaining
  n_r = pop_size - elite_count children round(crossover_fraction n_r) by crossover of two
  selected parents and the rest by mutation of one selected parent (crossover children are
  not mutated); the children replace the parents (generational). The toolbox documents
  CrossoverFraction as "the fraction of the population at the next generation, not
  including elite children, that the crossover function creates" (default 0.8) [1]. With
  pop_size 20, elite_count 2, fraction 0.7: 2 elite, 13 crossover, 5 mutation children,
  18 evaluations per generation; fraction 1.0 leaves no mutation children at all.
  ``elite_count`` = 2 is our assumption (the toolbox's default before R2014; the current
  documentation gives ceil(0.05 PopulationSize) = 1 [1]); no duplicate elimination.
  pymoo has no such split, so the mating and the replacement are written here
  (:class:`FractionMating`, :class:`ElitistReplacement`) around pymoo's operators;
- ``scheme: pymoo`` (ours, the earlier behaviour): crossover applied to a mating with
  probability ``crossover_fraction``, every child mutated (uniform reset only), duplicates
  eliminated, pymoo's survival keeps the best ``pop_size`` of parents and offspring.

Mutation (``mutation``, toolbox scheme; issue 27): three readings of the toolbox's mutation.
Two-point crossover of real genes only recombines the values the population already has, so
the mutation children are what creates new values, and the reading decides whether the GA
can refine a minimum (SPEC 4: the source's GA converged as tightly as its PSO and, without
mutation, did not converge).

- ``adaptive_feasible`` (default in the toolbox scheme; the replication's reading):
  the toolbox's mutationadaptfeasible, its default mutation for a problem with bounds or
  linear constraints. Documented as: "randomly generates directions that are adaptive with
  respect to the last successful or unsuccessful generation. The mutation chooses a
  direction and step length that satisfies bounds and linear constraints" [2]; the default
  mutationgaussian "is only appropriate for unconstrained minimization problems" [3]. The
  documentation gives no formulas; we follow the step rule and the bound handling of public
  functions derived from it [4] and the toolbox's mesh-adaptive poll directions [5]:
  a step size s = 1 in the first two generations, then s <- min(1, 4 s) after a generation
  that lowered the best value and s <- max(sqrt(eps), s / 4) after one that did not; each
  mutation child is its parent plus s times one direction of [B, -B, T, -T] (tried in random
  order, the first that stays in the bounds is taken, else the child is the parent), B a
  random lower-triangular basis with diagonal +-1/sqrt(s) and integers 0..1/sqrt(s) below
  it (rows and columns permuted), T the unit vectors along the bounds the parent lies on
  (within 1e-6, the older toolbox's TolCon). A step s moves each touched gene by about
  sqrt(s). Ours: it acts in the normalized box [0, 1]^k, not in physical units (the toolbox
  works in the units it is given; the source's scaling is not published), so s = 1 spans the
  whole box and the first two generations' mutation children stay at their parents; the
  rate ``mutation_rate`` is not used (the toolbox function has none) except that 0 switches
  mutation off (children = parents) as in every reading.
- ``gaussian``: the toolbox's mutationgaussian: every gene plus N(0, sd^2), sd = Scale x
  (range of the initial population) in the first generation, decreasing linearly "so that its
  final value equals 1 - Shrink times its initial value" at the last generation [3]; here
  sd = gaussian_scale (1 - gaussian_shrink g / generations) in generation g (not below 0),
  range 1 (the normalized box), ``generations`` = 100 (the toolbox's Generations default of
  the pre-R2014 releases, ours; later 100 x number of variables). Ours: children are clipped
  to the bounds (the toolbox's Gaussian mutation ignores bounds [3]); ``mutation_rate`` is
  not used except 0 = off.
- ``uniform`` (the reading used until issue 27; the pymoo scheme's only mutation): each gene
  is reset to a uniform random value in its bounds with probability ``mutation_rate`` (the
  toolbox's mutationuniform with Rate 0.01; pymoo has none for real variables, so it is
  written here).

Which reading is the source's GA (issue 27; lab frame, studies/lab_frame.yaml and
studies/selection_ga.yaml, 10 runs each, 10-generation stall window): adaptive feasible
converges in 10 of 10 runs to within 1e-5 of the best value any method finds, and in every
selection setting except fraction 1.0 without mutation, as the source's GA did; uniform and
Gaussian stall near 1e-3 (a uniform reset at rate 0.01 and a Gaussian of standard deviation
~0.9 of the range create values but cannot refine them). It is also the toolbox's default
for a bounded problem, which the source's was.

Sources (MathWorks documentation and MATLAB Answers, found with the project's search tool):
[1] ga / gamultiobj options table, mathworks.com/help/gads/gamultiobj.html (CrossoverFraction,
EliteCount); [2] MATLAB Answers 347865 "Constraint dependent in mutation" (quoting the
genetic-algorithm-options page) and 293589; [3] "Vary Mutation and Crossover",
mathworks.com/help/gads/vary-mutation-and-crossover.html (Gaussian Scale and Shrink, default
1 each), MATLAB Answers 350371, and "Set Maximum Number of Generations" (Gaussian shrink tied
to Generations; stall generations default 50); [4] public GA mutation functions "like
@mutationadaptfeasible" (e.g. github.com/Era-Dorta/fire-modeling,
heat_map/mutation_fnc/gamutationadaptscale.m); [5] the toolbox's boxdirections /
uncondirections (MADS random basis, pollParam = 1/sqrt(MeshSize)) as found in public copies.
No toolbox code is copied here; the operators are written from these descriptions.

The run's generator is pymoo's own ``default_rng(seed)``.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import Field, field_validator, model_validator

from framework.optimizers.base import Budget, Optimizer, Outcome, Settings, Termination
from framework.optimizers.pymoo_problem import pymoo_problem


class GASettings(Settings):
    pop_size: int = Field(20, ge=4)
    selection: Literal["tournament", "roulette"] = "tournament"
    crossover: Literal["single_point", "two_point", "scattered"] = "two_point"
    crossover_fraction: float = Field(0.7, ge=0, le=1)
    mutation_rate: float = Field(0.01, ge=0, le=1)
    scheme: Literal["toolbox", "pymoo"] = "toolbox"
    elite_count: int = Field(2, ge=0)
    mutation: Literal["uniform", "adaptive_feasible", "gaussian"] = "adaptive_feasible"
    gaussian_scale: float = Field(1.0, gt=0)
    gaussian_shrink: float = Field(1.0, ge=0, le=1)
    generations: int = Field(100, gt=0)

    @model_validator(mode="before")
    @classmethod
    def _default_mutation_by_scheme(cls, data):
        """Unset mutation: adaptive feasible in the toolbox scheme, uniform in the pymoo one."""
        if isinstance(data, dict) and data.get("mutation") is None and data.get("scheme") == "pymoo":
            data = {**data, "mutation": "uniform"}
        return data

    @field_validator("mutation")
    @classmethod
    def _mutation_needs_toolbox_scheme(cls, v, info):
        scheme = info.data.get("scheme")
        if v != "uniform" and scheme != "toolbox":
            raise ValueError(f"mutation {v!r} needs scheme 'toolbox' (the pymoo scheme mutates every child "
                             f"with the uniform reset); got scheme {scheme!r}")
        return v

    @field_validator("gaussian_scale", "gaussian_shrink", "generations")
    @classmethod
    def _gaussian_only(cls, v, info):
        # a default value is accepted (settings dumped with their defaults validate again)
        if info.data.get("mutation") != "gaussian" and v != cls.model_fields[info.field_name].default:
            raise ValueError(f"{info.field_name} applies to mutation 'gaussian' only; "
                             f"mutation is {info.data.get('mutation')!r}")
        return v


def children_split(pop_size: int, elite_count: int, crossover_fraction: float) -> dict[str, int]:
    """Children per generation in the toolbox scheme: elite, then round(fraction n_r) by
    crossover of the remaining n_r = pop_size - elite, the rest by mutation."""
    elite = min(elite_count, pop_size)
    rest = pop_size - elite
    crossover = int(round(crossover_fraction * rest))
    return {"elite": elite, "crossover": crossover, "mutation": rest - crossover}


class AdaptiveFeasibleMutation:
    """The toolbox's adaptive-feasible mutation on the box [0, 1]^k (module docstring).

    ``step`` starts at 1 for the first two generations; afterwards it is multiplied by 4
    (at most 1) after a generation that lowered the population's best value and divided by
    4 (at least sqrt(eps)) after one that did not. Each child moves from its parent by
    ``step`` times a random direction: a column of a random lower-triangular basis (diagonal
    +-1/sqrt(step), integers 0..1/sqrt(step) below it, rows and columns permuted), its
    negative, or a unit vector along a bound the parent lies on; the directions are tried in
    random order and the first that stays in the box is taken, else the child is the parent.
    """

    def __init__(self, tol: float = 1e-6):
        self.tol = tol
        self.step = 1.0
        self.bests: list[float] = []

    def update(self, best: float) -> float:
        """Record the population's best before a generation's children; return the step."""
        self.bests.append(best)
        if len(self.bests) > 2:
            improved = self.bests[-1] < self.bests[-2]
            self.step = min(1.0, 4.0 * self.step) if improved else max(np.sqrt(np.finfo(float).eps), self.step / 4.0)
        return self.step

    def directions(self, x: np.ndarray, rng) -> np.ndarray:
        """Trial directions (columns) for parent ``x`` in random order."""
        k = len(x)
        p = 1.0 / np.sqrt(self.step)
        lower = np.tril(np.round((p + 1.0) * rng.random((k, k)) - 0.5), -1)
        diag = p * np.where(rng.random(k) < 0.5, -1.0, 1.0)
        basis = lower + np.diag(diag)
        order = rng.permutation(k)
        basis = basis[np.ix_(order, order)]
        active = (np.abs(x) <= self.tol) | (np.abs(x - 1.0) <= self.tol)
        cone = np.eye(k)[:, active]
        dirs = np.hstack([basis, -basis, cone, -cone])
        return dirs[:, rng.permutation(dirs.shape[1])]

    def __call__(self, X: np.ndarray, rng) -> np.ndarray:
        out = np.array(X, dtype=float, copy=True)
        for i, x in enumerate(out):
            for d in self.directions(x, rng).T:
                trial = x + self.step * d
                if np.all(trial >= -self.tol) and np.all(trial <= 1.0 + self.tol):
                    out[i] = np.clip(trial, 0.0, 1.0)
                    break
        return out


class GaussianMutation:
    """The toolbox's Gaussian mutation on [0, 1]^k (module docstring): every gene plus
    N(0, sd^2), sd = scale (1 - shrink g / generations) in generation g (at least 0),
    the child clipped to the box (ours: the toolbox's Gaussian mutation ignores bounds)."""

    def __init__(self, scale: float, shrink: float, generations: int):
        self.scale, self.shrink, self.generations = scale, shrink, generations
        self.generation = 0
        self.sd = scale

    def update(self, best: float) -> float:
        self.generation += 1
        self.sd = max(0.0, self.scale * (1.0 - self.shrink * self.generation / self.generations))
        return self.sd

    def __call__(self, X: np.ndarray, rng) -> np.ndarray:
        X = np.asarray(X, dtype=float)
        return np.clip(X + self.sd * rng.standard_normal(X.shape), 0.0, 1.0)


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

    if s.mutation == "adaptive_feasible":
        mutation = AdaptiveFeasibleMutation()
    elif s.mutation == "gaussian":
        mutation = GaussianMutation(s.gaussian_scale, s.gaussian_shrink, s.generations)
    else:
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
            if s.mutation != "uniform":  # the step (adaptive) or scale (Gaussian) of this generation
                F = np.asarray(pop.get("F"), dtype=float)[:, 0]
                mutation.update(float(np.min(F[np.isfinite(F)])) if np.isfinite(F).any() else np.inf)
            if n_x:
                pairs = selection(problem, pop, n_x, n_parents=2, random_state=random_state, **kwargs)
                kids = crossover(problem, pairs, random_state=random_state, **kwargs)
                parts.append(kids[:n_x])  # rows: first child of every pair, then the second ones
            if n_m:
                single = selection(problem, pop, n_m, n_parents=1, random_state=random_state, **kwargs)
                X = np.array([row[0].get("X") for row in single], dtype=float)
                if s.mutation == "uniform":
                    X = mutation._do(problem, X, random_state=random_state)
                elif s.mutation_rate > 0:  # rate 0: no mutation in any reading (children = parents)
                    X = mutation(X, random_state)
                parts.append(Population.new(X=X))
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


def run(evaluator, seed: int, budget: Budget, s: GASettings) -> Outcome:
    from pymoo.algorithms.soo.nonconvex.ga import GA
    from pymoo.operators.sampling.rnd import FloatRandomSampling
    from pymoo.termination.max_gen import MaximumGenerationTermination

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
               "scheme": s.scheme, "elite_count": s.elite_count if s.scheme == "toolbox" else None,
               "mutation": s.mutation},
    )


OPTIMIZER = Optimizer("ga", GASettings, run)
