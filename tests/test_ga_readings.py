"""Issue 27: the readings of the GA toolbox's mutation (framework/optimizers/ga.py).

The replication's reading (adaptive feasible, the toolbox's default for a bounded problem)
converges on the lab frame; the earlier per-gene uniform reset is kept as ``mutation:
uniform`` with its old numbers; without mutation no new gene values appear."""

from __future__ import annotations

import numpy as np
import pytest
from pydantic import ValidationError

from framework.optimizers import ga, run_optimizer
from framework.optimizers.base import Budget
from framework.structures.lab_frame import model as lf
from framework.updating.problem import UpdatingProblem

#: studies/lab_frame.yaml's termination (SPEC 4) and the best value any method finds there
LAB_BUDGET = Budget(max_evaluations=50_000, stall_iterations=10, stall_tolerance=1e-8, target_objective=1e-6)
F_STAR = 1.6476e-6
LAB_GA = {"pop_size": 20, "selection": "tournament", "crossover": "two_point", "crossover_fraction": 0.7,
          "mutation_rate": 0.01, "scheme": "toolbox", "elite_count": 2}


@pytest.fixture(scope="module")
def lab():
    return UpdatingProblem(lf.make_model(), lf.measured())


def test_default_reading_is_adaptive_feasible_and_converges_on_the_lab_frame(lab):
    assert ga.GASettings().mutation == "adaptive_feasible"
    for seed in (0, 1, 2):
        r = run_optimizer("ga", lab, seed=seed, budget=LAB_BUDGET, **LAB_GA)
        assert r.extra["mutation"] == "adaptive_feasible"
        assert r.status == "stalled"
        assert r.objective - F_STAR < 1e-5  # the acceptance, run by run
        assert r.n_evaluations < 5_000  # well inside the budget (about 50-150 generations)


@pytest.mark.parametrize("seed, objective, evaluations", [
    (0, 0.004733539565382816, 326), (1, 0.0018239795958132448, 236), (2, 0.0012282853765696463, 398),
])
def test_uniform_option_gives_the_earlier_runs(lab, seed, objective, evaluations):
    # the committed results/lab_frame GA runs made before issue 27 (per-gene uniform reset)
    r = run_optimizer("ga", lab, seed=seed, budget=LAB_BUDGET, **LAB_GA, mutation="uniform")
    assert r.n_evaluations == evaluations
    assert r.objective == pytest.approx(objective, rel=1e-9)


def _evaluated_points(monkeypatch, lab, **settings) -> np.ndarray:
    """Every point the GA evaluates, in order (normalized coordinates)."""
    seen = []
    original = ga.pymoo_problem

    def recording(evaluator):
        problem = original(evaluator)
        inner = problem._evaluate

        def _evaluate(X, out, *args, **kwargs):
            seen.append(np.array(X, dtype=float, copy=True))
            return inner(X, out, *args, **kwargs)

        problem._evaluate = _evaluate
        return problem

    monkeypatch.setattr(ga, "pymoo_problem", recording)
    run_optimizer("ga", lab, seed=4, budget=Budget(max_evaluations=400, stall_iterations=1000), **settings)
    return np.vstack(seen)


@pytest.mark.parametrize("mutation", ["uniform", "adaptive_feasible", "gaussian"])
@pytest.mark.parametrize("fraction", [1.0, 0.7])
def test_without_mutation_no_new_gene_values_appear(monkeypatch, lab, mutation, fraction):
    X = _evaluated_points(monkeypatch, lab, crossover_fraction=fraction, mutation_rate=0.0, mutation=mutation)
    initial, later = X[:20], X[20:]
    assert len(later) == 18 * 21
    for j in range(X.shape[1]):  # crossover only recombines: every gene value is an initial one
        assert np.isin(later[:, j], initial[:, j]).all()


def test_with_mutation_new_gene_values_appear(monkeypatch, lab):
    X = _evaluated_points(monkeypatch, lab, crossover_fraction=0.7, mutation_rate=0.01)
    initial, later = X[:20], X[20:]
    assert not np.isin(later[:, 0], initial[:, 0]).all()
    assert ((X >= 0.0) & (X <= 1.0)).all()  # kept in the box


def test_adaptive_feasible_step_grows_after_success_and_shrinks_after_failure():
    m = ga.AdaptiveFeasibleMutation()
    # generations 1, 2: step 1; then x4 (at most 1) after an improvement, /4 after none
    steps = [m.update(b) for b in (5.0, 4.0, 4.0, 3.0, 3.0, 3.0, 2.0)]
    assert steps == [1.0, 1.0, 0.25, 1.0, 0.25, 0.0625, 0.25]
    for _ in range(40):
        m.update(2.0)
    assert m.step == pytest.approx(np.sqrt(np.finfo(float).eps))


def test_adaptive_feasible_children_stay_in_the_box_and_move_by_about_sqrt_step():
    rng = np.random.default_rng(0)
    m = ga.AdaptiveFeasibleMutation()
    m.step = 1.0 / 64  # 1/sqrt(step) = 8: each touched gene moves by a multiple of 1/64, at most 1/8
    X = np.vstack([rng.random((50, 6)), np.zeros((1, 6)), np.ones((1, 6))])
    kids = m(X, rng)
    assert ((kids >= 0.0) & (kids <= 1.0)).all()
    move = np.abs(kids - X)
    assert (move.max(axis=1) > 0).all()  # a feasible direction exists from every parent, corners included
    assert move.max() <= 8 / 64 + 1e-12
    assert np.allclose(np.round(move * 64), move * 64)
    # at step 1 no direction from an interior point stays in [0, 1]: the child is the parent
    m.step = 1.0
    inner = np.full((3, 6), 0.5)
    assert np.array_equal(m(inner, rng), inner)


def test_gaussian_scale_shrinks_linearly_over_the_generations():
    m = ga.GaussianMutation(scale=1.0, shrink=1.0, generations=100)
    sds = [m.update(0.0) for _ in range(101)]
    assert sds[0] == pytest.approx(0.99) and sds[49] == pytest.approx(0.5) and sds[99] == 0.0 and sds[100] == 0.0
    m = ga.GaussianMutation(scale=0.5, shrink=0.5, generations=10)
    assert [m.update(0.0) for _ in range(10)][-1] == pytest.approx(0.25)
    kids = m(np.full((200, 6), 0.99), np.random.default_rng(1))
    assert ((kids >= 0.0) & (kids <= 1.0)).all() and (kids == 1.0).any()  # clipped to the box


@pytest.mark.parametrize("settings, where, message", [
    ({"mutation": "adaptive"}, "mutation", "Input should be 'uniform', 'adaptive_feasible' or 'gaussian'"),
    ({"scheme": "pymoo", "mutation": "adaptive_feasible"}, "mutation", "needs scheme 'toolbox'"),
    ({"gaussian_scale": 0.5}, "gaussian_scale", "applies to mutation 'gaussian' only"),
    ({"mutation": "uniform", "generations": 50}, "generations", "applies to mutation 'gaussian' only"),
    ({"mutation": "gaussian", "gaussian_shrink": 1.5}, "gaussian_shrink", "less than or equal to 1"),
    ({"mutation": "gaussian", "generations": 0}, "generations", "greater than 0"),
])
def test_settings_validation(settings, where, message):
    with pytest.raises(ValidationError, match=message) as info:
        ga.GASettings.model_validate(settings, strict=True)
    assert info.value.errors()[0]["loc"] == (where,)


def test_scheme_decides_the_unset_mutation():
    assert ga.GASettings(scheme="pymoo").mutation == "uniform"
    assert ga.GASettings(scheme="toolbox").mutation == "adaptive_feasible"
    assert ga.GASettings(mutation="gaussian", generations=600).generations == 600
    for mutation in ("uniform", "adaptive_feasible", "gaussian"):  # dumped settings validate again (study plans)
        s = ga.GASettings(mutation=mutation)
        assert ga.GASettings.model_validate(s.model_dump(mode="json"), strict=True) == s


def test_a_bad_mutation_in_a_config_is_one_line_naming_the_field(tmp_path):
    from framework.core.errors import InputError
    from framework.study.config import load

    path = tmp_path / "study.yaml"
    path.write_text("study: t\nstructure: {name: lab_frame_3dof}\nmeasured: {builtin: lab_frame, case: base}\n"
                    "algorithms:\n  ga: {algorithm: ga, settings: {scheme: pymoo, mutation: gaussian}}\n")
    with pytest.raises(InputError, match="settings.mutation: .*needs scheme 'toolbox'") as info:
        load(path)
    assert str(path) in str(info.value) and "\n" not in str(info.value)
