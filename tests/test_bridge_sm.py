"""The source's sensitivity method (SM ``method: pseudo_inverse``, used by the bridge study):
P_k+1 = clip(P_k - S^+ r(P_k)), S by one-sided differences, n + 1 model runs per iteration.

Checked on the cheap 3-DOF lab frame with three parameters and the frequency term only (an
exact fit exists), and on the same problem with a bound cutting off the exact fit."""

import numpy as np
import pytest

from framework.optimizers import Budget, run_optimizer
from framework.optimizers.sm import SMSettings, difference_points, pseudo_inverse_step
from framework.structures.lab_frame.model import make_model, measured
from framework.updating.objectives import ObjectiveSpec
from framework.updating.problem import UpdatingProblem

NAMES = ["kyy", "kxx", "krr"]
BUDGET = Budget(max_evaluations=400, target_objective=None, stall_tolerance=0.0)


def frequency_problem(bounds=None) -> UpdatingProblem:
    model = make_model()
    params = model.parameters.subset(NAMES)
    if bounds:
        params = params.with_bounds(bounds)
    return UpdatingProblem(model, measured(), parameters=params, objective=ObjectiveSpec(beta=0.0))


def test_difference_points_step_back_at_the_upper_bound():
    points, h = difference_points(np.array([0.2, 1.0, 0.9995]), 1e-3)
    np.testing.assert_allclose(h, [1e-3, -1e-3, -1e-3])
    assert points.shape == (4, 3) and np.all((points >= 0) & (points <= 1))
    np.testing.assert_allclose(points[1:] - points[0], np.diag(h))


def test_pseudo_inverse_step_is_the_least_squares_solution():
    rng = np.random.default_rng(0)
    jac, r = rng.normal(size=(8, 3)), rng.normal(size=8)
    np.testing.assert_allclose(pseudo_inverse_step(jac, r, 1e-12), -np.linalg.lstsq(jac, r, rcond=None)[0])
    # rank-deficient: the minimum-norm step
    jac[:, 2] = jac[:, 1]
    step = pseudo_inverse_step(jac, r, 1e-12)
    assert step[1] == pytest.approx(step[2])


def test_pseudo_inverse_finds_the_exact_fit_with_n_plus_one_runs_per_iteration():
    problem = frequency_problem()
    pinv = run_optimizer("sm", problem, 0, BUDGET, method="pseudo_inverse")
    trust = run_optimizer("sm", problem, 0, BUDGET)
    assert pinv.status == "converged" and pinv.objective < 1e-15
    assert pinv.n_evaluations == pinv.n_iterations * (len(NAMES) + 1)
    np.testing.assert_allclose(pinv.theta_best, trust.theta_best, rtol=1e-6)
    steps = [it["max_step"] for it in pinv.extra["iterations"]]
    assert steps[-1] < SMSettings().step_tolerance and all(not it["clipped"] for it in pinv.extra["iterations"])


def test_a_step_beyond_a_bound_is_clipped_after_the_step():
    """kxx's exact fit (17349 N/m) lies below the bound 18000: every step that crosses it is
    clipped, and the iteration stops on the bound (a fixed point of the projected step)."""
    problem = frequency_problem({"kxx": (18000.0, 24500.0)})
    res = run_optimizer("sm", problem, 0, BUDGET, method="pseudo_inverse")
    assert res.status == "converged"
    theta = dict(zip(NAMES, res.theta_best))
    assert theta["kxx"] == pytest.approx(18000.0)
    assert res.extra["final_clipped"] == ["kxx"]
    assert res.objective > 1e-6  # the exact fit is out of reach
    assert res.extra["condition_number"] > 1.0 and len(res.extra["singular_values"]) == len(NAMES)


def test_pseudo_inverse_run_is_reproducible_and_stops_on_the_budget():
    problem = frequency_problem()
    a = run_optimizer("sm", problem, 0, Budget(max_evaluations=10), method="pseudo_inverse", start_factor=1.1)
    b = run_optimizer("sm", problem, 0, Budget(max_evaluations=10), method="pseudo_inverse", start_factor=1.1)
    assert a.status == "budget" and a.n_evaluations == 8 and a.n_iterations == 2  # a third would need 12
    np.testing.assert_array_equal(a.x_best, b.x_best)
    assert a.extra == b.extra
