"""Core layer: stateless problem, per-run evaluator, one termination rule, failed runs,
the objective schema and the static formulation registry."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from framework.core.errors import InputError
from framework.optimizers import OPTIMIZERS, Budget, run_optimizer
from framework.optimizers.base import Termination
from framework.optimizers.niching import derated
from framework.structures.lab_frame.model import make_model, measured
from framework.updating.evaluator import BudgetExhausted, Evaluator
from framework.updating.formulations import FORMULATIONS
from framework.updating.objectives import ObjectiveSpec, RatioConstraint
from framework.updating.problem import UpdatingProblem

ROOT = Path(__file__).resolve().parents[1]
TESTS = Path(__file__).resolve().parent

#: small settings of every optimizer for a 6-parameter problem and a budget of a few hundred
SMALL = {
    "pso": {"swarm_size": 10},
    "ga": {"pop_size": 10},
    "annealing": {"max_iterations": 20},
    "sm": {"start": "random"},
    "snt": {"n_minima": 2, "pso": {"swarm_size": 10}},
    "nsga2": {"pop_size": 12, "n_generations": 8},
    "hybrid": {"global": {"algorithm": "pso", "settings": {"swarm_size": 10}, "max_evaluations": 150}},
    "multistart": {"n_starts": 4, "batch_size": 2},
}


def lab_problem(**objective) -> UpdatingProblem:
    return UpdatingProblem(make_model(), measured(), objective=ObjectiveSpec(**objective) if objective else None)


def holey_problem(kxx_limit: float = 21000.0, **objective):
    """The lab frame whose evaluations with kxx above ``kxx_limit`` fail (kxx in [16000, 24500])."""
    sys.path.insert(0, str(TESTS))
    import fault_models

    return UpdatingProblem(fault_models.make_holey(kxx_limit), measured(),
                           objective=ObjectiveSpec(**objective) if objective else None)  # fmt: skip


def _same(a, b):
    assert a.status == b.status and a.n_evaluations == b.n_evaluations and a.n_iterations == b.n_iterations
    np.testing.assert_array_equal(a.x_best, b.x_best)
    assert a.objective == b.objective or (np.isnan(a.objective) and np.isnan(b.objective))
    np.testing.assert_array_equal(a.history, b.history)
    assert a.extra == b.extra


# ---- stateless problem, per-run evaluator ---------------------------------------------------
def test_every_optimizer_is_covered():
    assert set(SMALL) == set(OPTIMIZERS)


@pytest.mark.parametrize("algorithm", sorted(SMALL))
def test_a_reused_problem_gives_the_same_result_as_a_fresh_one(algorithm):
    budget = Budget(max_evaluations=300)
    fresh = run_optimizer(algorithm, lab_problem(), 4, budget, **SMALL[algorithm])
    reused = lab_problem()
    for other in ("sm", "pso"):  # runs before on the same object leave nothing behind
        run_optimizer(other, reused, 9, budget, **SMALL[other])
    again = run_optimizer(algorithm, reused, 4, budget, **SMALL[algorithm])
    _same(fresh, again)
    assert 0 < again.n_evaluations <= budget.max_evaluations
    assert again.history.shape == (again.n_evaluations,)
    json.dumps(again.extra, allow_nan=True)  # extra is plain JSON data


def test_pso_after_sm_reports_its_own_point_and_count():
    problem = lab_problem()
    sm = run_optimizer("sm", problem, 0, Budget(max_evaluations=2000))
    pso = run_optimizer("pso", problem, 1, Budget(max_evaluations=100), swarm_size=10)
    assert pso.n_evaluations == 100 and pso.objective > sm.objective
    assert pso.objective == pytest.approx(np.nanmin(pso.history))
    assert pso.objective == pytest.approx(problem.objective1(pso.x_best), rel=1e-12)


def test_problem_is_immutable_and_evaluate_is_pure():
    problem = lab_problem()
    X = np.random.default_rng(0).random((5, 6))
    a, b = problem.evaluate(X), problem.evaluate(X)
    np.testing.assert_array_equal(a.objective, b.objective)
    np.testing.assert_allclose(np.sum(a.residuals**2, axis=1), a.objective)
    np.testing.assert_allclose(a.objectives.sum(axis=1), a.objective)
    with pytest.raises(AttributeError, match="immutable"):
        problem.spec = ObjectiveSpec(alpha=2.0)
    assert not hasattr(problem, "log") and not hasattr(problem, "reset") and not hasattr(problem, "runner")
    with pytest.raises(ValueError, match="NaN"):
        problem.evaluate(np.full((1, 6), np.nan))


@pytest.mark.parametrize(
    "args, argument",
    [
        ((make_model(), {"f": [1.0]}), "measured"),
        (({"kxx": 1.0}, measured()), "model"),
        ((make_model(), measured(), {"kxx": (1, 2)}), "parameters"),
        ((make_model(), measured(), None, {"alpha": 1.0}), "objective"),
    ],
)
def test_wrong_argument_types_name_the_argument(args, argument):
    with pytest.raises(InputError, match=f"argument '{argument}' must be"):
        UpdatingProblem(*args)


def test_evaluator_counts_budgets_and_records_failures():
    problem = holey_problem()
    calls = []
    ev = Evaluator(problem, max_evaluations=10, progress=calls.append)
    X = np.random.default_rng(1).random((6, 6))
    out = ev.evaluate(X)
    assert ev.n_evaluations == 6 and calls == [6] and ev.remaining == 4 and ev.affords(4) and not ev.affords(5)
    assert ev.n_failed == int((~out.ok).sum()) > 0 and set(ev.failures) == {"not_converged"}
    assert ev.best_objective == pytest.approx(out.objective[out.ok].min())
    with pytest.raises(BudgetExhausted):
        ev.evaluate(X[:5])
    assert ev.n_evaluations == 6  # nothing was evaluated
    child = ev.child(derated(problem, [ev.best_x], 0.5, 0.1), max_evaluations=3)
    child.objective1(X[0])
    assert child.n_evaluations == 1 and ev.n_evaluations == 7 and child.remaining == 2 and calls == [6, 1]


def test_sensitivities_are_not_counted_and_widen_keeps_steps_forward():
    from framework.updating.sensitivity import sensitivity_matrix

    # torsion in sensor units (theta b/2): at the all-upper corner every mode stays paired
    # (in radians, the default reading, the 1st x mode pairs with no model mode there)
    problem = UpdatingProblem(make_model(congruence="model"), measured(congruence="model"))
    at_upper = problem.parameters.upper.copy()
    backward = sensitivity_matrix(problem, theta0=at_upper)
    forward = sensitivity_matrix(problem, theta0=at_upper, widen=(0.01, 4.0))
    assert backward.frequency.shape == (3, 6) and np.all(np.isfinite(forward.frequency))
    # a one-sided difference: the two agree to first order
    np.testing.assert_allclose(backward.frequency, forward.frequency, rtol=0.05, atol=1e-3)
    r = run_optimizer("pso", problem, 0, Budget(max_evaluations=20), swarm_size=10)
    assert r.n_evaluations == 20


# ---- one termination rule ---------------------------------------------------------------------
def test_termination_rules():
    ev = Evaluator(lab_problem(), 100)
    t = Termination(Budget(stall_iterations=2, stall_tolerance=0.1, target_objective=None), ev)
    assert t.update(1.0) is None and t.update(0.95) is None and t.update(0.94) == "stalled"
    t = Termination(Budget(target_objective=0.5), ev)
    assert t.update(1.0) is None and t.update(0.4) == "target" and t.status == "target"
    t = Termination(Budget(max_iterations=2, target_objective=None), ev, rules=("max_iterations",))
    assert t.update(1.0) is None and t.update(1.0) == "max_iterations"
    assert Termination(Budget(), ev).status == "budget" and t.affords(100) and not t.affords(101)


def test_snt_respects_the_total_budget():
    budget = Budget(max_evaluations=400, stall_iterations=10**6, stall_tolerance=0.0, target_objective=None)
    r = run_optimizer("snt", lab_problem(), 0, budget, n_minima=3, pso={"swarm_size": 20})
    assert r.n_evaluations <= 400
    minima = r.extra["minima"]
    assert len(minima) == 3 and sum(m["n_evaluations"] for m in minima) == r.n_evaluations
    # 400 / 3 -> 133 (6 iterations of 20 = 120), then 280 / 2 = 140 (140), then 140
    assert [m["n_evaluations"] for m in minima] == [120, 140, 140]


def test_snt_niche_searches_stop_at_the_stall_rule():
    budget = Budget(max_evaluations=30_000, stall_iterations=5, stall_tolerance=1e-3, target_objective=None)
    r = run_optimizer("snt", lab_problem(), 0, budget, n_minima=2, pso={"swarm_size": 10})
    assert [m["status"] for m in r.extra["minima"]] == ["stalled", "stalled"]
    assert r.n_evaluations < 1000


def test_nsga2_stops_at_the_budget_and_at_the_stall_rule():
    no_stall = Budget(max_evaluations=10 * 7, target_objective=None, stall_tolerance=0.0)
    r = run_optimizer("nsga2", lab_problem(), 0, no_stall, pop_size=10, n_generations=50)
    assert r.status == "budget" and r.n_evaluations == 70 and r.extra["generations_run"] == 7
    stall = Budget(max_evaluations=10**6, stall_iterations=3, stall_tolerance=1.0, target_objective=None)
    r = run_optimizer("nsga2", lab_problem(), 0, stall, pop_size=10, n_generations=50)
    # the first generation sets the reference; three more without improvement stop the run
    assert r.status == "stalled" and r.n_iterations == 4 and r.n_evaluations == 40


def test_nsga2_run_through_the_study_executor_is_not_an_error():
    from framework.study.config import validate
    from framework.study.execute import execute_run
    from framework.study.plan import plan

    cfg = validate({
        "study": "nsga2_small", "structure": {"name": "lab_frame_3dof"},
        "measured": {"builtin": "lab_frame", "case": "base"},
        "budget": {"max_evaluations": 60},
        "algorithms": {"nsga2": {"algorithm": "nsga2", "settings": {"pop_size": 10, "n_generations": 6}}},
        "runs": 1, "execution": {"progress": False},
    })  # fmt: skip
    tables = execute_run(plan(cfg)[0])
    run = tables["runs"][0]
    assert run["status"] != "error" and run["n_evaluations"] == 60, run.get("error")
    pareto = json.loads(next(r["value"] for r in tables["extra"] if r["key"] == "pareto_F"))
    assert len(pareto) >= 1 and len(pareto[0]) == 2


# ---- failed runs are not results ------------------------------------------------------------------
def test_a_run_whose_evaluations_all_failed_is_failed():
    problem = holey_problem(kxx_limit=15000.0)
    for algorithm in ("sm", "pso"):
        r = run_optimizer(algorithm, problem, 0, Budget(max_evaluations=40), **SMALL[algorithm])
        assert r.status == "failed" and np.isnan(r.objective) and np.isnan(r.theta_best).all()
        assert r.n_failed == r.n_evaluations > 0 and "not_converged" in r.failures
        assert "every evaluation failed" in r.message


@pytest.mark.parametrize("algorithm", ["pso", "ga", "sm", "annealing", "nsga2"])
def test_a_failed_point_is_never_the_result_even_with_a_tiny_penalty(algorithm):
    limit = 21000.0
    settings = SMALL[algorithm]
    if algorithm == "sm":  # start below the limit; the minimum (kxx 17336) lies beyond it
        limit = 17000.0
        problem = holey_problem(limit)
        x0 = problem.x_initial.copy()
        x0[problem.parameters.names.index("kxx")] = 0.05
        settings = {"x0": x0.tolist()}
    problem = holey_problem(limit, failure_penalty=1e-9)
    r = run_optimizer(algorithm, problem, 2, Budget(max_evaluations=200), **settings)
    assert r.n_failed > 0 and r.status != "failed"
    assert r.theta_best[problem.parameters.names.index("kxx")] <= limit
    assert problem.evaluate(r.x_best[None, :]).ok[0]
    assert r.objective > 1e-9
    # the failed points' Pi (1e-9) is below the target (1e-6); only a successful point may meet it
    assert r.status != "target"


# ---- objective schema and formulations --------------------------------------------------------------
@pytest.mark.parametrize(
    "fields, message",
    [
        ({"alpha": 0.0, "beta": 0.0}, "alpha and beta are both 0"),
        ({"failure_penalty": 0.0}, "objective.failure_penalty: Input should be greater than 0"),
        ({"failure_penalty": float("inf")}, "objective.failure_penalty: Input should be a finite number"),
        ({"alpha": True}, "objective.alpha: expected a number"),
        ({"pairing": "nearest"}, "objective.pairing"),
        ({"formulation": "nope"}, "objective.formulation: unknown formulation 'nope'"),
        ({"formulation": "reference", "options": {"matching": "x"}}, "objective.options: matching must be one of"),
        ({"formulation": "gaussian", "options": {"unmatched_window": -1}}, "objective.options: unmatched_window"),
        ({"ratio_constraints": [{"numerator": "kxx"}]}, "objective.ratio_constraints.0.denominator: Field required"),
        ({"alpah": 1.0}, "objective.alpah: unknown key"),
    ],
)
def test_objective_spec_rejects_bad_values_naming_the_field(fields, message):
    with pytest.raises(InputError, match=message.replace("(", r"\(")):
        ObjectiveSpec(**fields)


def test_objective_spec_keeps_keyword_and_config_construction():
    spec = ObjectiveSpec(alpha=2, frequency_window=0.25, ratio_constraints=(RatioConstraint("kxx", "kyy", 1e-4),))
    assert spec.alpha == 2.0 and spec.ratio_constraints[0].weight == 1e-4
    same = ObjectiveSpec.model_validate(spec.model_dump())
    assert same == spec
    assert ObjectiveSpec() == ObjectiveSpec(alpha=1.0, beta=1.0, failure_penalty=1e3, formulation="spec")


def test_alpha_zero_without_shapes_is_rejected_by_the_problem():
    data = measured()
    from framework.measured.modes import MeasuredModes

    no_shapes = MeasuredModes(data.frequencies_hz)
    with pytest.raises(InputError, match="identically 0"):
        UpdatingProblem(make_model(), no_shapes, objective=ObjectiveSpec(alpha=0.0))


def test_every_formulation_validates_in_a_fresh_interpreter():
    code = (
        "from framework.updating.formulations import FORMULATIONS\n"
        "from framework.updating.objectives import ObjectiveSpec\n"
        "for name in FORMULATIONS:\n"
        "    assert ObjectiveSpec(formulation=name).formulation == name\n"
        "print(sorted(FORMULATIONS))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT,
                         env={"PYTHONPATH": str(ROOT), "PATH": ""}, timeout=120)  # fmt: skip
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == str(sorted(FORMULATIONS)) == "['gaussian', 'reference', 'spec']"
