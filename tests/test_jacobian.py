"""Exact Jacobians from modal derivatives agree with central finite differences.

Agreement is measured per block of residuals (frequency/eigenvalue terms, shape terms,
penalty terms) as max |J - J_fd| / max |J_fd| over the block, at random points. The central
differences are Richardson-extrapolated (steps h and h/2), and h is chosen per model, so
that neither their truncation error nor the eigen solver's round-off divided by h comes
near the tolerances.
"""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest

from framework.core.modal_derivatives import CloseEigenvalues
from framework.core.parameters import Parameter, ParameterSet
from framework.measured.modes import MeasuredModes
from framework.models.matrix import MatrixModel
from framework.optimizers import Budget, run_optimizer
from framework.structures.beam import model as beam
from framework.structures.smu import model as smu
from framework.updating.objectives import ObjectiveSpec
from framework.updating.problem import UpdatingProblem

needs_smu = pytest.mark.skipif(not smu.available(), reason=f"SMU data not found in {smu.smu_dir()}")
FREQUENCY_RTOL = 1e-6
SHAPE_RTOL = 1e-5


def central_jacobian(problem: UpdatingProblem, x: np.ndarray, step_theta: float) -> np.ndarray:
    """Central differences D(h) of the residuals with Richardson extrapolation, (4 D(h/2) - D(h)) / 3,
    which cancels their O(h^2) error; h is ``step_theta`` in physical units (over x's span)."""
    span = problem.parameters.upper - problem.parameters.lower
    J = np.empty((problem.n_residuals, x.size))
    for j in range(x.size):
        d = []
        for h in (step_theta / span[j], 0.5 * step_theta / span[j]):
            e = np.zeros(x.size)
            e[j] = h
            d.append((problem.residuals(x + e) - problem.residuals(x - e)) / (2.0 * h))
        J[:, j] = (4.0 * d[1] - d[0]) / 3.0
    return J


def block_errors(problem: UpdatingProblem, J: np.ndarray, J_fd: np.ndarray) -> dict[str, float]:
    m = problem.measured.n_modes
    blocks = {"frequency": slice(0, m), "shape": slice(m, problem.n_modal_residuals),
              "penalty": slice(problem.n_modal_residuals, problem.n_residuals)}
    out = {}
    for name, rows in blocks.items():
        if J[rows].size:
            out[name] = float(np.abs(J[rows] - J_fd[rows]).max() / np.abs(J_fd[rows]).max())
    return out


def assert_agrees(problem: UpdatingProblem, x: np.ndarray, step_theta: float) -> dict[str, float]:
    jac = problem.jacobian(x)
    assert jac.method == "exact", jac.reason
    errors = block_errors(problem, jac.J, central_jacobian(problem, x, step_theta))
    assert errors["frequency"] < FREQUENCY_RTOL, errors
    assert errors.get("shape", 0.0) < SHAPE_RTOL, errors
    assert errors.get("penalty", 0.0) < FREQUENCY_RTOL, errors
    return errors


# ---- beam (numpy model: K linear in the I ratios, massless rotations) ------------------------
@pytest.mark.parametrize("seed", [0, 1])
def test_beam_spec_jacobian_with_penalties(seed):
    model = beam.make_model("apriori", n_modes=7)
    spec = ObjectiveSpec(regularization_tau=0.01,
                         ratio_constraints=[{"numerator": "ratio_03", "denominator": "ratio_06", "weight": 0.05}])
    problem = UpdatingProblem(model, beam.measured("state1", noise_pct=2.0, seed=3), objective=spec)
    x = np.random.default_rng(seed).uniform(0.2, 0.8, problem.n_params)
    errors = assert_agrees(problem, x, 1e-4)
    assert set(errors) == {"frequency", "shape", "penalty"}


def test_beam_reference_eigenvector_jacobian():
    model = beam.make_model("apriori", n_modes=7)
    spec = ObjectiveSpec(formulation="reference", options={"matching": "order", "weights": "unit",
                                                           "shape_term": "eigenvector"})
    problem = UpdatingProblem(model, beam.measured("state2", noise_pct=1.0, seed=1), objective=spec)
    assert problem.n_modal_residuals == 5 * 9  # 5 eigenvalue terms + 5 x 8 shape entries
    assert_agrees(problem, np.random.default_rng(5).uniform(0.2, 0.8, problem.n_params), 1e-4)


def test_beam_derivative_of_a_uniform_stiffness_scaling():
    """K -> s K: lambda scales with s (sum_e dlambda/dr_e = lambda at r = 1), shapes do not change."""
    model = beam.make_model("apriori", n_modes=5)
    result = model.modal({})
    d = model.modal_derivatives({}, result)
    np.testing.assert_allclose(d.dlambda.sum(axis=1), result.meta["omega2"], rtol=1e-10)
    assert np.abs(d.dphi.sum(axis=2)).max() < 1e-9 * np.abs(d.dphi).max()
    assert d.cost == 5 and d.parameters == tuple(model.parameters.names)


# ---- SMU benchmarks ----------------------------------------------------------------------------
@needs_smu
@pytest.mark.parametrize("options", [
    {"formulation": "reference", "options": {"matching": "order", "weights": "unit"}},
    {"formulation": "reference", "options": {"matching": "order", "weights": "unit", "shape_term": "eigenvector"}},
    {"formulation": "spec"},
])
def test_four_story_jacobian(options):
    model = smu.make_four_story(measured_floors=[1, 2, 3, 4], n_modes=4)
    problem = UpdatingProblem(model, smu.four_story_measured("base"), objective=ObjectiveSpec(**options))
    rng = np.random.default_rng(11)
    for _ in range(2):
        assert_agrees(problem, rng.uniform(0.25, 0.75, 4), 1e-4)


@needs_smu
@pytest.mark.parametrize("shape_term, solver", [("mac", "shift_invert"), ("eigenvector", "shift_invert"),
                                                ("mac", "shift_invert_ldl"), ("eigenvector_smu_as_run", "shift_invert_ldl")])
def test_footbridge_jacobian(shape_term, solver):
    """946 DOFs, singular M (474 massless DOFs), 17 parameters, sparse Nelson; also on the
    modes of the reused-LDL' solver, and with the eigenvector weights of the SMU package's runs."""
    if solver == "shift_invert_ldl":
        pytest.importorskip("qdldl")
    options = {"matching": "order", "weights": "std", "shape_term": shape_term}
    if shape_term == "eigenvector_smu_as_run":
        options.update(shape_term="eigenvector", eigenvector_weights="smu_as_run")
    spec = ObjectiveSpec(formulation="reference", options=options)
    problem = UpdatingProblem(smu.make_footbridge(solver=solver), smu.footbridge_measured(), objective=spec)
    x = problem.x_initial + np.random.default_rng(2).uniform(-0.05, 0.05, problem.n_params)
    assert problem.jacobian(x).cost == 5  # one factorization per measured mode
    assert_agrees(problem, x, 1e-3)


# ---- bridge fast path (OpenSees gravity, extracted K; cable tangents differenced) ----------------
def test_bridge_fast_path_jacobian():
    from framework.structures import bridge

    objective = ObjectiveSpec(pairing="mac", frequency_window=0.25,
                              ratio_constraints=[{"numerator": "K_t_deck", "denominator": "K_bearing"}])
    problem = UpdatingProblem(bridge.make_model(4, fast=True), bridge.measured(), objective=objective)
    x = np.random.default_rng(4).uniform(0.3, 0.7, problem.n_params)
    assert problem.jacobian_cost_bound == 8 + 1 + 2 * 6
    assert_agrees(problem, x, 1e-3)


# ---- the eigenvector formulation by hand -------------------------------------------------------
def _diagonal_model(name: str = "diagonal", lower: float = -0.5, upper: float = 4.0) -> MatrixModel:
    """K = diag(1 (1 + a_1), 4 (1 + a_2), 9 (1 + a_3)), M = I: modes are the unit vectors."""
    parts = [np.diag([1.0, 0, 0]), np.diag([0, 4.0, 0]), np.diag([0, 0, 9.0])]
    params = ParameterSet(Parameter(f"a_{i + 1}", 0.0, lower, upper) for i in range(3))
    return MatrixModel(parts, np.eye(3), params, {"u1": 0, "u2": 1, "u3": 2}, n_modes=3, name=name)


def _f_hz(lam: float) -> float:
    return math.sqrt(lam) / (2.0 * math.pi)


def test_eigenvector_residuals_by_hand():
    """Modes e1 (lambda 1), e2 (lambda 4). Measured lambda 1.25 and 5: eigenvalue terms
    (1.25 - 1)/1.25 = 0.2 and (5 - 4)/5 = 0.2. Shape 1 = [1, 0.2, -0.1] is normalized at
    entry 1 (it is 1 there): psi_e - psi_a = [0.2, -0.1] at entries 2, 3, weighted by
    1/(3 std) = [10, 5]/3 (3 measured DOFs) -> [2/3, -1/6]. Shape 2 = [0.3, 1, 0] (reference
    entry 2): [0.3, 0] at entries 1, 3, weighted [10, 2]/3 -> [1.0, 0.0]. With
    eigenvector_weights 'smu_as_run' mode i's entries are all weighted 1/(3 std(i, 1)):
    mode 1 1/(3 * 0) is the reference entry's zero -> an input error; with std(1, 1) = 0.05
    mode 1 is weighted 20/3 -> [4/3, -2/3] and mode 2 1/(3 * 0.1) -> [1.0, 0.0]."""
    measured = MeasuredModes(
        frequencies_hz=np.array([_f_hz(1.25), _f_hz(5.0)]),
        dofs=("u1", "u2", "u3"),
        shapes=np.array([[1.0, 0.3], [0.2, 1.0], [-0.1, 0.0]]),
        shape_std=np.array([[0.0, 0.1], [0.1, 0.0], [0.2, 0.5]]),
        name="hand",
    )
    spec = ObjectiveSpec(formulation="reference",
                         options={"matching": "order", "weights": "std", "shape_term": "eigenvector"})
    problem = UpdatingProblem(_diagonal_model(), measured, objective=spec)
    r = problem.residuals(problem.x_initial)
    np.testing.assert_allclose(r, [0.2, 0.2, 2 / 3, -1 / 6, 1.0, 0.0], atol=1e-12)
    pi_lam, pi_shape = problem.objectives(problem.x_initial[None, :])[0]
    assert pi_lam == pytest.approx(0.08) and pi_shape == pytest.approx(4 / 9 + 1 / 36 + 1.0)
    # the weights the SMU package's code applied (its published results)
    from framework.core.errors import InputError

    as_run = ObjectiveSpec(formulation="reference", options={
        "matching": "order", "weights": "std", "shape_term": "eigenvector", "eigenvector_weights": "smu_as_run"})
    with pytest.raises(InputError, match="shape_std of mode 1 at DOF 'u1' is zero"):
        UpdatingProblem(_diagonal_model(), measured, objective=as_run)
    measured.shape_std[0, 0] = 0.05
    r = UpdatingProblem(_diagonal_model(), measured, objective=as_run).residuals(problem.x_initial)
    np.testing.assert_allclose(r, [0.2, 0.2, 4 / 3, -2 / 3, 1.0, 0.0], atol=1e-12)
    # mac stays the default shape term
    mac = UpdatingProblem(_diagonal_model(), measured, objective=ObjectiveSpec(
        formulation="reference", options={"matching": "order", "weights": "unit"}))
    assert mac.n_residuals == 4


def test_eigenvector_option_is_checked():
    from framework.core.errors import InputError

    with pytest.raises(InputError, match="shape_term must be one of"):
        ObjectiveSpec(formulation="reference", options={"shape_term": "modal_residual"})


# ---- close eigenvalues --------------------------------------------------------------------------
def test_close_eigenvalues_fall_back_to_finite_differences(caplog):
    """a_1 = 3 (1 + 1e-9): lambda_1 = 4 (1 + 1e-9) next to lambda_2 = 4, a relative gap of 1e-9."""
    model = _diagonal_model(name="diagonal_close")
    measured = MeasuredModes(frequencies_hz=np.array([_f_hz(4.2), _f_hz(4.5), _f_hz(9.3)]), dofs=("u1", "u2", "u3"),
                             shapes=np.eye(3), name="close")
    problem = UpdatingProblem(model, measured, objective=ObjectiveSpec(pairing="order", use_shapes=False))
    x = problem.parameters.to_normalized(np.array([3.0 * (1 + 1e-9), 0.0, 0.0]))
    with pytest.raises(CloseEigenvalues, match="relative gap"):
        model.modal_derivatives(problem.parameters.as_dict(problem.theta(x)))
    with caplog.at_level(logging.WARNING, logger="framework.updating.problem"):
        first = problem.jacobian(x)
        second = problem.jacobian(x)
    assert first.method == "fd" and first.reason.startswith("close_eigenvalues") and first.cost == 3
    assert sum("finite-difference Jacobian" in rec.message for rec in caplog.records) == 1  # warned once
    np.testing.assert_array_equal(first.J, second.J)
    # the fallback is the forward difference with step 1e-3 in x
    step = np.zeros(3)
    step[2] = 1e-3
    expected = (problem.residuals(x + step) - problem.residuals(x)) / 1e-3
    np.testing.assert_allclose(first.J[:, 2], expected, rtol=1e-12)
    # away from the crossing the Jacobian is exact again
    assert problem.jacobian(problem.x_initial).method == "exact"


def test_failed_derivatives_fall_back_to_finite_differences():
    from framework.core.errors import ModelEvaluationError

    class Broken(MatrixModel):
        def modal_derivatives(self, theta, result=None, **kwargs):
            raise ModelEvaluationError("not_converged", "gravity analysis at theta + h")

    model = _diagonal_model()
    broken = Broken([np.diag([1.0, 0, 0]), np.diag([0, 4.0, 0]), np.diag([0, 0, 9.0])], np.eye(3), model.parameters,
                    {"u1": 0, "u2": 1, "u3": 2}, n_modes=3, name="broken")
    measured = MeasuredModes(frequencies_hz=np.array([_f_hz(1.1), _f_hz(4.4)]), dofs=("u1", "u2", "u3"),
                             shapes=np.eye(3)[:, :2], name="two")
    jac = UpdatingProblem(broken, measured).jacobian(np.full(3, 0.3))
    assert jac.method == "fd" and jac.reason.startswith("derivatives_failed: ModelEvaluationError")
    exact = UpdatingProblem(model, measured).jacobian(np.full(3, 0.3))
    np.testing.assert_allclose(jac.J, exact.J, atol=1e-3 * np.abs(exact.J).max())


# ---- the sensitivity method with the exact Jacobian ---------------------------------------------
@needs_smu
def test_sm_exact_jacobian_counts_and_reaches_the_optimum_in_fewer_evaluations():
    model = smu.make_four_story(measured_floors=[1, 2, 3, 4], n_modes=4)
    spec = ObjectiveSpec(formulation="reference", options={"matching": "order", "weights": "unit"})
    problem = UpdatingProblem(model, smu.four_story_measured("base"), objective=spec)
    budget = Budget(max_evaluations=20000, stall_iterations=50, stall_tolerance=1e-12, target_objective=None)
    fd, exact = [], []
    for seed in (2, 3, 4):  # starts in the optimum's basin (seeds 0 and 1 end in the local minimum 0.0152)
        fd.append(run_optimizer("sm", problem, seed, budget, start="random", jacobian="fd"))
        exact.append(run_optimizer("sm", problem, seed, budget, start="random"))  # auto -> exact
    for a, b in zip(fd, exact):
        assert b.extra["jacobian"] == "exact" and a.extra["jacobian"] == "fd"
        assert b.objective < 1.60442e-7 and b.objective <= a.objective * (1 + 1e-6)
        # every Jacobian differentiates the 2 measured modes: 2 eigen-solve equivalents
        assert b.extra["jacobian_equivalents"] == 2 * b.n_jacobians
        assert b.n_evaluations > b.extra["jacobian_equivalents"]
        assert len(b.history) == b.n_evaluations
        assert a.n_jacobians == a.n_iterations
    assert sum(r.n_evaluations for r in exact) < 0.8 * sum(r.n_evaluations for r in fd)


def test_sm_exact_needs_derivatives():
    from framework.structures.lab_frame import model as lab_frame

    problem = UpdatingProblem(lab_frame.make_model(), lab_frame.measured())
    with pytest.raises(ValueError, match="jacobian 'exact' needs a model with modal_derivatives"):
        run_optimizer("sm", problem, 0, Budget(max_evaluations=50), jacobian="exact")
    auto = run_optimizer("sm", problem, 0, Budget(max_evaluations=50))
    assert auto.extra["jacobian"] == "fd"


def test_evaluator_jacobian_budget_and_history():
    from framework.updating.evaluator import BudgetExhausted, Evaluator

    problem = UpdatingProblem(beam.make_model("apriori", n_modes=7), beam.measured("state1"))
    evaluator = Evaluator(problem, max_evaluations=7)
    x = problem.x_initial
    evaluator.residuals(x)
    J = evaluator.jacobian(x)  # reuses the evaluation of x: 5 paired modes = 5 equivalents
    np.testing.assert_allclose(J, problem.jacobian(x).J, rtol=1e-12)
    assert (evaluator.n_evaluations, evaluator.n_jacobians, evaluator.jacobian_equivalents) == (6, 1, 5)
    assert len(evaluator.history()) == 6 and np.all(evaluator.history() == evaluator.history()[0])
    with pytest.raises(BudgetExhausted):
        evaluator.jacobian(x)  # the bound (5) exceeds the 1 evaluation left


# ---- the four-storey study's formulations, as a small study --------------------------------------
@needs_smu
def test_four_story_study_formulations_serial_and_processes(tmp_path):
    """The sweep formulation x shape_term plans the spec runs once; SM's exact Jacobians are
    counted in the runs table; serial and process execution give the same tables."""
    from pathlib import Path

    import pandas as pd

    from framework.study.config import load, validate
    from framework.study.plan import plan
    from framework.study.runner import run_study

    config = Path(__file__).resolve().parents[1] / "studies" / "external_four_story.yaml"
    data = load(config).model_dump(mode="json")
    assert len(plan(load(config))) == 5 * 10 * 3  # reference x {mac, eigenvector}, spec once
    data.update(runs=2, report={}, algorithms={"sm": {"algorithm": "sm", "settings": {"start": "random"}}})
    tables = {}
    for backend in ("serial", "processes"):
        cfg = validate(dict(data, output=str(tmp_path / backend),
                            execution={"backend": backend, "workers": 2, "progress": False}))
        run_study(cfg, figures=False)
        tables[backend] = pd.read_csv(tmp_path / backend / "runs.csv").drop(columns=["wall_s"])
    pd.testing.assert_frame_equal(tables["serial"], tables["processes"], check_exact=True)
    runs = tables["serial"]
    assert sorted(set(zip(runs["formulation"], runs["shape_term"]))) == [
        ("reference", "eigenvector"), ("reference", "mac"), ("spec", "mac")]
    assert (runs["n_jacobians"] > 0).all() and (runs["jacobian"] == "auto").all()
    # every Jacobian costs 2 eigen-solve equivalents (2 measured modes) after at least one evaluation
    assert (runs["n_evaluations"] >= 3 * runs["n_jacobians"]).all()
