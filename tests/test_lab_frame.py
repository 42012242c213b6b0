"""3-DOF laboratory frame: initial frequencies, vectorized path, added mass, updating."""

import numpy as np
import pytest

from framework.optimizers import Budget, run_optimizer
from framework.structures.lab_frame.model import CASES, make_model, mass_matrix, measured, stiffness_matrix
from framework.updating.problem import UpdatingProblem


def test_initial_frequencies_match_spec():
    f = make_model().modal({}).frequencies_hz
    assert 3.58 <= f[0] <= 3.59
    assert f[1] == pytest.approx(5.42, abs=0.005)
    assert f[2] == pytest.approx(7.85, abs=0.005)


def test_initial_objective_is_about_1e_2():
    p = UpdatingProblem(make_model(), measured())
    assert 0.01 < p.objective1(p.x_initial) < 0.015


def test_stiffness_matrix_symmetric_and_eccentricity_terms():
    K = stiffness_matrix(2.0, 3.0, 0.5, 7.0, 0.1, -0.2)
    np.testing.assert_allclose(K, K.T)
    assert K[0, 2] == pytest.approx(-2.0 * -0.2 + 0.5 * 0.1)
    assert K[2, 2] == pytest.approx(2.0 * 0.04 - 2 * 0.5 * 0.1 * -0.2 + 3.0 * 0.01 + 7.0)


def test_batch_equals_single_point():
    model = make_model()
    rng = np.random.default_rng(3)
    thetas = [model.parameters.as_dict(model.parameters.to_physical(x)) for x in rng.random((7, 6))]
    for single, batch in zip((model.modal(t) for t in thetas), model.modal_batch(thetas)):
        np.testing.assert_allclose(batch.frequencies_hz, single.frequencies_hz, rtol=1e-12)
        np.testing.assert_allclose(np.abs(batch.shapes), np.abs(single.shapes), rtol=1e-9, atol=1e-12)


def test_added_mass_lowers_all_frequencies_and_keeps_static_moments():
    base = make_model().modal({}).frequencies_hz
    heavy = make_model(case="mass_1.379kg").modal({}).frequencies_hz
    assert np.all(heavy < base)
    M0, M1 = mass_matrix(), mass_matrix(added_mass_kg=1.379)
    assert M1[0, 0] == pytest.approx(17.5 + 1.379)
    np.testing.assert_allclose(M1[0, 2], M0[0, 2])
    assert set(CASES) == {"base", "mass_0.654kg", "mass_1.379kg"}


@pytest.mark.parametrize(
    "algorithm, settings, budget",
    [
        ("sm", {"start": "initial"}, Budget(max_evaluations=2000)),
        ("sm", {"start": "random"}, Budget(max_evaluations=2000)),
        ("annealing", {}, Budget(max_evaluations=8000)),
        # the toolbox scheme (the source's GA) stalls near 2e-4 within this budget; the
        # (mu + lambda) pymoo scheme reaches the minimum
        ("ga", {"scheme": "pymoo"}, Budget(max_evaluations=15000, stall_iterations=100)),
        ("pso", {}, Budget(max_evaluations=4000, stall_iterations=50)),
    ],
)
@pytest.mark.parametrize("seed", [0, 1])
def test_every_algorithm_updates_to_below_1e_4(algorithm, settings, budget, seed):
    p = UpdatingProblem(make_model(), measured())
    before = p.objective1(p.x_initial)
    r = run_optimizer(algorithm, p, seed=seed, budget=budget, **settings)
    assert before > 1e-2
    assert r.objective < 1e-4
    assert r.n_evaluations <= budget.max_evaluations
    table = p.mode_table(r.theta_best)
    assert table["matched"].all()
    assert table["error_pct"].abs().max() < 0.05
    assert np.all(r.theta_best >= p.parameters.lower) and np.all(r.theta_best <= p.parameters.upper)


def test_sensitivity_method_reports_condition_number_and_counts_jacobian_evaluations():
    p = UpdatingProblem(make_model(), measured())
    r = run_optimizer("sm", p, seed=0)
    assert r.extra["condition_number"] > 1
    # each iteration spends n+1 evaluations on the forward-difference Jacobian
    assert r.n_evaluations >= r.n_iterations * (p.n_params + 1)
    # minimum of the default torsion congruence ("measured"; "model" gives 1.593e-5)
    # (SM from the initial point ends at 1.72e-6, just above the minimum 1.648e-6)
    assert 1.64e-6 < r.objective < 1.8e-6


@pytest.mark.parametrize("algorithm", ["pso", "ga", "annealing", "sm", "snt"])
def test_same_seed_same_result(algorithm):
    settings = {"start": "random"} if algorithm == "sm" else {}
    b = Budget(max_evaluations=600)
    out = []
    for _ in range(2):
        p = UpdatingProblem(make_model(), measured())
        r = run_optimizer(algorithm, p, seed=7, budget=b, **settings)
        out.append((r.objective, r.x_best.copy(), r.n_evaluations, r.history.copy()))
    assert out[0][0] == out[1][0]
    np.testing.assert_array_equal(out[0][1], out[1][1])
    assert out[0][2] == out[1][2]
    np.testing.assert_array_equal(out[0][3], out[1][3])


def test_sm_starts_from_an_explicit_point():
    p = UpdatingProblem(make_model(), measured())
    x0 = np.full(6, 0.3)
    r = run_optimizer("sm", p, seed=0, budget=Budget(max_evaluations=7), x0=x0.tolist())
    np.testing.assert_allclose(r.extra["x_start"], x0)
    with pytest.raises(ValueError, match="x0 must be 6 finite numbers"):
        run_optimizer("sm", p, seed=0, x0=[0.5, 0.5])


def test_pso_leaves_global_numpy_state_untouched():
    np.random.seed(123)
    expected = np.random.random()
    np.random.seed(123)
    run_optimizer("pso", UpdatingProblem(make_model(), measured()), seed=1, budget=Budget(max_evaluations=200))
    assert np.random.random() == expected


def test_snt_reports_raw_and_derated_minima():
    p = UpdatingProblem(make_model(), measured())
    r = run_optimizer("snt", p, seed=0, budget=Budget(max_evaluations=1500), n_minima=3)
    minima = r.extra["minima"]
    assert len(minima) == 3
    assert r.extra["niche_radius"] == pytest.approx(np.sqrt(6) / (2 * 3 ** (1 / 6)))
    assert minima[0]["raw_objective"] == pytest.approx(minima[0]["derated_objective"])
    for m in minima:
        assert m["derated_objective"] >= m["raw_objective"] - 1e-12
        differs = not np.isclose(m["raw_objective"], m["derated_objective"], rtol=1e-9, atol=1e-15)
        assert m["inside_niche"] == differs
        assert m["artefact"] == (differs or m["on_niche_boundary"])
    assert r.objective == min(m["raw_objective"] for m in minima)
