"""NSGA-II adapter: first-front cap, nearest-to-ideal choice, budget, reproducibility."""

import numpy as np
import pytest

from framework.core.parameters import Parameter, ParameterSet
from framework.damage import estimation as damage
from framework.optimizers import Budget, run_optimizer
from framework.optimizers.nsga2 import _survival_class, nearest_to_ideal
from framework.structures.beam import model as beam
from framework.updating.problem import Evaluations, UpdatingProblem


class ToyBiObjective:
    """f1 = x0, f2 = (1 - x0)^2 + sum(x[1:]^2): Pareto set x[1:] = 0, front f2 = (1 - f1)^2.

    ``fail_above``: points with x0 above it fail (objectives = ``penalty``)."""

    def __init__(self, k=3, fail_above=None, penalty=1e3):
        self.parameters = ParameterSet(Parameter(f"x{i}", 0.5, 0.0, 1.0) for i in range(k))
        self.n_params = k
        self.n_objectives = 2
        self.x_initial = self.parameters.x_initial
        self.fail_above, self.penalty = fail_above, penalty

    def evaluate(self, X, runner=None):
        X = np.clip(np.atleast_2d(np.asarray(X, float)), 0, 1)
        F = np.column_stack([X[:, 0], (1 - X[:, 0]) ** 2 + np.sum(X[:, 1:] ** 2, axis=1)])
        ok = np.ones(len(X), bool) if self.fail_above is None else X[:, 0] <= self.fail_above
        F[~ok] = self.penalty
        reasons = [None if o else "toy_failure" for o in ok]
        return Evaluations(F.sum(axis=1), np.sqrt(F), F, ok, reasons, ["" if o else "x0 too large" for o in ok],
                           [None] * len(X))  # fmt: skip


def test_nearest_to_ideal_uses_normalized_objectives():
    F = np.array([[0.0, 100.0], [0.5, 10.0], [1.0, 0.0]])
    assert nearest_to_ideal(F) == 1
    assert nearest_to_ideal(np.array([[3.0, 4.0]])) == 0


def test_survival_caps_first_front_share():
    from pymoo.core.population import Population

    front = np.column_stack([np.linspace(0, 1, 10), np.linspace(1, 0, 10)])
    dominated = front + 2.0
    from pymoo.core.problem import Problem

    problem = Problem(n_var=1, n_obj=2, xl=0.0, xu=1.0)
    pop = Population.new("F", np.vstack([front, dominated]))
    survivors = _survival_class()(0.35).do(problem, pop, n_survive=10)
    ranks = survivors.get("rank")
    assert len(survivors) == 10 and np.sum(ranks == 0) == 4
    # extreme points of the first front (infinite crowding) are kept
    kept = survivors.get("F")[ranks == 0]
    assert {0.0, 1.0} <= set(np.round(kept[:, 0], 6))
    plain = _survival_class()(1.0).do(problem, Population.new("F", np.vstack([front, dominated])), n_survive=10)
    assert np.sum(plain.get("rank") == 0) == 10


def test_nsga2_on_toy_front_and_reproducible():
    problem = ToyBiObjective()
    budget = Budget(max_evaluations=40 * 30, target_objective=None, stall_tolerance=0.0)  # only the budget ends it
    res = run_optimizer("nsga2", problem, 5, budget, pop_size=40, n_generations=60)
    assert res.n_evaluations == 40 * 30 and res.extra["generations_run"] == 30 and res.status == "budget"
    F, X = np.array(res.extra["pareto_F"]), np.array(res.extra["pareto_X"])
    assert F.shape[1] == 2 and X.shape == (len(F), 3)
    # points lie near the true front f2 = (1 - f1)^2
    assert np.median(np.abs(F[:, 1] - (1 - F[:, 0]) ** 2)) < 0.02
    assert res.extra["chosen_index"] == nearest_to_ideal(F)
    np.testing.assert_allclose(res.x_best, X[res.extra["chosen_index"]])
    again = run_optimizer("nsga2", ToyBiObjective(), 5, budget, pop_size=40, n_generations=60)
    np.testing.assert_array_equal(np.array(again.extra["pareto_F"]), F)


def test_nsga2_rejects_unknown_setting():
    with pytest.raises(ValueError, match="population"):
        run_optimizer("nsga2", ToyBiObjective(), 0, Budget(), population=10)


def test_nsga2_two_state_beam_small():
    model = beam.make_model()
    p1 = UpdatingProblem(model, beam.measured("state1", 0.0, 0))
    p2 = UpdatingProblem(model, beam.measured("state2", 0.0, 0))
    tp = damage.two_state(p1, p2)
    budget = Budget(max_evaluations=10**6, target_objective=None, stall_tolerance=0.0)
    res = run_optimizer("nsga2", tp, 1, budget, pop_size=60, n_generations=15)
    # a two-state point runs the model twice
    assert res.theta_best.shape == (20,) and res.n_evaluations == 2 * 60 * 15
    chosen = np.array(res.extra["chosen_F"])
    np.testing.assert_allclose(chosen, [p1.objective1(res.x_best[:10]), p2.objective1(res.x_best[10:])], rtol=1e-10)
    # the search improves on its random initial population (history per model evaluation)
    best_of_first_generation = res.history[2 * 60 - 1]
    assert chosen.sum() < best_of_first_generation
