"""Vectorized evaluation of small models: the array path (one batched eigh, batched MAC and
pairing, no per-point objects) gives the numbers of the per-point path."""

from dataclasses import dataclass

import numpy as np
import pytest

from framework.models.arrays import ModalArrays, array_method
from framework.structures.lab_frame.model import PARAMETERS, ThreeDofFrame, make_model, measured
from framework.updating.objectives import ObjectiveSpec, RatioConstraint
from framework.updating.pairing import ModeCorrelations
from framework.updating.problem import UpdatingProblem

SPECS = [
    ObjectiveSpec(),
    ObjectiveSpec(frequency_window=0.05, mac_threshold=0.99),
    ObjectiveSpec(beta=0.0),
    ObjectiveSpec(use_shapes=False),
    ObjectiveSpec(pairing="order"),
    ObjectiveSpec(pairing="frequency", frequency_window=0.1),
    ObjectiveSpec(regularization_tau=0.01, regularization_space="normalized", ratio_constraints=(RatioConstraint("kxx", "kyy", 1e-3),)),
]


def _per_point_runner(model, thetas):
    """One ModalResult per point, as the process and Dask runners return them."""
    return model.modal_batch(thetas)


def _assert_same(a, b, rtol=1e-12):
    np.testing.assert_array_equal(a.ok, b.ok)
    assert a.reasons == b.reasons and a.details == b.details
    np.testing.assert_allclose(a.objective, b.objective, rtol=rtol, atol=0)
    np.testing.assert_allclose(a.residuals, b.residuals, rtol=rtol, atol=1e-15)
    np.testing.assert_allclose(a.objectives, b.objectives, rtol=rtol, atol=1e-15)
    assert len(a.correlations) == len(b.correlations)
    for ca, cb in zip(a.correlations, b.correlations):
        assert (ca is None) == (cb is None)
        if ca is not None:
            np.testing.assert_array_equal(ca.analytical_index, cb.analytical_index)
            np.testing.assert_array_equal(ca.matched, cb.matched)
            np.testing.assert_allclose(ca.f_model_hz, cb.f_model_hz, rtol=rtol)
            np.testing.assert_allclose(ca.mac, cb.mac, rtol=rtol, atol=1e-15)


@pytest.mark.parametrize("spec", SPECS, ids=range(len(SPECS)))
def test_array_path_equals_the_per_point_path(spec):
    problem = UpdatingProblem(make_model(), measured(), objective=spec)
    X = np.random.default_rng(3).random((40, 6))
    fast = problem.evaluate(X)
    assert isinstance(fast.correlations, ModeCorrelations)  # no per-point objects were built
    one_by_one = [problem.evaluate(x[None, :]) for x in X]
    assert np.all(fast.ok)
    np.testing.assert_allclose(fast.objective, [e.objective[0] for e in one_by_one], rtol=1e-12, atol=0)
    np.testing.assert_allclose(fast.residuals, np.vstack([e.residuals for e in one_by_one]), rtol=1e-12,
                               atol=1e-15)
    for i, e in enumerate(one_by_one):
        c, d = fast.correlations[i], e.correlations[0]
        np.testing.assert_array_equal(c.analytical_index, d.analytical_index)
        np.testing.assert_allclose(c.f_model_hz, d.f_model_hz, rtol=1e-12)
        np.testing.assert_allclose(c.frequency_error, d.frequency_error, rtol=1e-10, atol=1e-15)


@pytest.mark.parametrize("spec", SPECS[:3], ids=range(3))
def test_array_path_is_bitwise_the_runner_path(spec):
    """In process (arrays) and through a runner (one ModalResult per point): the same numbers,
    so a run gives the same result on every backend."""
    problem = UpdatingProblem(make_model(), measured(), objective=spec)
    X = np.random.default_rng(4).random((30, 6))
    _assert_same(problem.evaluate(X), problem.evaluate(X, _per_point_runner), rtol=0)


def test_failed_points_are_reported_as_on_the_per_point_path():
    # a coupling stiffness beyond sqrt(kxx kyy) makes K indefinite
    params = PARAMETERS.with_bounds({"kxy": (-30000.0, 30000.0)})
    problem = UpdatingProblem(make_model(), measured(), parameters=params)
    X = np.random.default_rng(5).random((60, 6))
    fast = problem.evaluate(X)
    assert 0 < int((~fast.ok).sum()) < len(X)
    assert set(r for r in fast.reasons if r) == {"indefinite_matrix"}
    np.testing.assert_allclose(fast.objective[~fast.ok], problem.spec.failure_penalty, rtol=1e-12)
    assert all(fast.correlations[i] is None for i in np.flatnonzero(~fast.ok))
    _assert_same(fast, problem.evaluate(X, _per_point_runner), rtol=0)
    singles = [problem.evaluate(x[None, :]) for x in X]
    assert [s.reasons[0] for s in singles] == fast.reasons
    np.testing.assert_allclose(fast.objective, [s.objective[0] for s in singles], rtol=1e-12)


@dataclass(frozen=True)
class _DeadSensorFrame(ThreeDofFrame):
    """The frame whose shapes vanish at every measured DOF for kxx above a limit (MAC undefined)."""

    def modal_arrays(self, theta, names):
        out = super().modal_arrays(theta, names)
        shapes = out.shapes.copy()
        shapes[np.asarray(theta)[:, list(names).index("kxx")] > 21000.0] = 0.0
        return ModalArrays(out.frequencies_hz, shapes, out.dofs, out.errors)


def test_points_with_vanishing_shapes_fail_with_the_per_point_message():
    problem = UpdatingProblem(_DeadSensorFrame(), measured())
    X = np.random.default_rng(6).random((20, 6))
    fast = problem.evaluate(X)
    dead = problem.parameters.to_physical(X)[:, 1] > 21000.0
    assert dead.any() and not dead.all()
    np.testing.assert_array_equal(fast.ok, ~dead)
    assert {fast.reasons[i] for i in np.flatnonzero(dead)} == {"correlation_failed"}
    assert "zero norm" in fast.details[int(np.flatnonzero(dead)[0])]
    _assert_same(fast, problem.evaluate(X, _per_point_runner), rtol=0)


def test_array_method_respects_overrides():
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import fault_models

    assert array_method(make_model()) is not None
    assert array_method(_DeadSensorFrame()) is not None
    assert array_method(fault_models.make_holey(21000.0)) is None  # overrides modal and modal_batch
    assert array_method(fault_models.DyingFrame(marker="x")) is None  # modal_batch = None
    holey = UpdatingProblem(fault_models.make_holey(21000.0), measured())
    X = np.random.default_rng(7).random((20, 6))
    ev = holey.evaluate(X)
    assert set(r for r in ev.reasons if r) == {"not_converged"}
    np.testing.assert_array_equal(ev.ok, holey.parameters.to_physical(X)[:, 1] <= 21000.0)


def test_lazy_correlations_behave_like_a_list():
    problem = UpdatingProblem(make_model(), measured())
    X = np.random.default_rng(8).random((5, 6))
    corr = problem.evaluate(X).correlations
    assert len(corr) == 5 and len(list(corr)) == 5 and len(corr[1:3]) == 2
    table = problem.mode_table(problem.theta(X[2]))
    np.testing.assert_allclose(table["f_model_hz"], corr[2].f_model_hz, rtol=1e-12)
    np.testing.assert_allclose(table["mac"], corr[2].mac, rtol=1e-12)
