"""Bring-your-own OpenSeesPy model: a user's build function through OpenSeesModel."""

import math
import pickle

import numpy as np
import pytest

from framework.core.errors import ModelEvaluationError
from framework.core.parameters import Parameter, ParameterSet
from framework.measured.modes import MeasuredModes
from framework.models.opensees import OpenSeesModel
from framework.optimizers import Budget, run_optimizer
from framework.updating.evaluator import Evaluator
from framework.updating.problem import UpdatingProblem

ops = pytest.importorskip("openseespy.opensees")

L, N_EL, A, I_M4, RHO_A = 2.0, 10, 0.01, 8.33e-6, 78.5  # steel-like cantilever, mass per length kg/m


def build_cantilever(v):
    """A user's build function: 2D cantilever of elastic beam elements with lumped masses."""
    ops.model("basic", "-ndm", 2, "-ndf", 3)
    for i in range(N_EL + 1):
        ops.node(i + 1, 0.0, i * L / N_EL)
    ops.fix(1, 1, 1, 1)
    ops.geomTransf("Linear", 1)
    for i in range(N_EL):
        ops.element("elasticBeamColumn", i + 1, i + 1, i + 2, A, v["E"], I_M4, 1, "-mass", RHO_A, "-cMass")
    return {"nodes": N_EL + 1}


PARAMS = ParameterSet([Parameter("E", 2.0e11, 1.0e11, 3.0e11, "Pa", "Young's modulus")])
DOFS = {f"n{i}_x": (i, "ux") for i in (4, 7, 11)}


def model(**kw):
    return OpenSeesModel(build_cantilever, PARAMS, DOFS, n_modes=3, solver="-fullGenLapack", **kw)


def test_first_frequency_matches_euler_bernoulli():
    f1 = model().modal({}).frequencies_hz[0]
    exact = 1.8751**2 / (2 * math.pi * L**2) * math.sqrt(2.0e11 * I_M4 / RHO_A)
    assert f1 == pytest.approx(exact, rel=2e-3)


def test_shapes_at_measured_dofs_and_scaling():
    r = model().modal({})
    assert r.dofs == tuple(DOFS)
    assert r.shapes.shape == (3, 3)
    assert abs(r.shapes[2, 0]) > abs(r.shapes[0, 0])  # tip moves more than a node near the root
    scaled = model(dof_scale={"n11_x": 2.0}).modal({})
    np.testing.assert_allclose(np.abs(scaled.shapes[2]), 2 * np.abs(r.shapes[2]), rtol=1e-9)


def test_frequency_scales_with_sqrt_of_stiffness():
    f0 = model().modal({"E": 2.0e11}).frequencies_hz
    f1 = model().modal({"E": 2.88e11}).frequencies_hz
    np.testing.assert_allclose(f1 / f0, 1.2, rtol=1e-6)


def test_model_is_picklable_and_updates_from_measured_data():
    m = pickle.loads(pickle.dumps(model()))
    truth = m.modal({"E": 2.4e11})
    data = MeasuredModes(truth.frequencies_hz[:2], tuple(DOFS), truth.shapes[:, :2])
    p = UpdatingProblem(m, data)
    r = run_optimizer("sm", p, seed=0, budget=Budget(max_evaluations=60, target_objective=None))
    assert r.theta_best[0] == pytest.approx(2.4e11, rel=1e-4)


def _bad_build(v):
    ops.model("basic", "-ndm", 2, "-ndf", 3)
    ops.node(1, 0.0, 0.0)
    ops.node(2, 0.0, 1.0)
    ops.geomTransf("Linear", 1)
    ops.element("elasticBeamColumn", 1, 1, 2, A, v["E"], I_M4, 1)
    ops.mass(2, 1.0, 1.0, 0.0)  # no supports: singular stiffness


def _raising_build(v):
    raise ValueError("section table missing")


def test_failures_become_reasons_not_crashes():
    p = UpdatingProblem(OpenSeesModel(_raising_build, PARAMS, {"a": (2, 1)}, n_modes=1),
                        MeasuredModes(np.array([1.0])))
    ev = p.evaluate(np.array([[0.5]]))
    assert not ev.ok[0] and ev.reasons[0] == "build_failed"
    assert ev.objective[0] == pytest.approx(p.spec.failure_penalty)
    assert "section table missing" in ev.details[0]
    with pytest.raises(ModelEvaluationError, match="build_failed: ValueError: section table missing"):
        OpenSeesModel(_raising_build, PARAMS, {"a": (2, 1)}, n_modes=1).modal({})


def test_singular_model_fails_with_a_reason():
    # an unsupported frame: the stiffness of its massless DOFs is singular
    m = OpenSeesModel(_bad_build, PARAMS, {"a": (2, 1)}, n_modes=2)
    p = UpdatingProblem(m, MeasuredModes(np.array([1.0])))
    ev = p.evaluate(np.array([[0.5], [0.6]]))
    assert not ev.ok.any()
    assert ev.reasons == ["singular_matrix", "singular_matrix"]
    r = run_optimizer("pso", p, seed=0, budget=Budget(max_evaluations=4), swarm_size=2)
    assert r.status == "failed" and r.n_failed == 4 and "singular_matrix x4" in r.failures
    assert np.isnan(r.objective) and np.isnan(r.theta_best).all()
    # OpenSees' ARPACK: its shift-invert fails on the singular stiffness
    arpack = UpdatingProblem(OpenSeesModel(_bad_build, PARAMS, {"a": (2, 1)}, n_modes=2, solver="-genBandArpack"),
                             MeasuredModes(np.array([1.0])))
    assert arpack.evaluate(np.array([[0.5]])).reasons == ["eigen_failed"]


def test_unknown_direction_is_rejected():
    with pytest.raises(ValueError, match="unknown direction 'uq'"):
        OpenSeesModel(build_cantilever, PARAMS, {"a": (2, "uq")})


def _exiting_build(v):
    raise SystemExit("licence server unreachable")


def test_sys_exit_in_a_build_is_a_failure_not_the_end_of_the_study():
    p = UpdatingProblem(OpenSeesModel(_exiting_build, PARAMS, {"a": (2, 1)}, n_modes=1),
                        MeasuredModes(np.array([1.0])))
    evaluator = Evaluator(p)
    ev = evaluator.evaluate(np.array([[0.5]]))
    assert not ev.ok[0] and ev.reasons == ["model_exit"]
    assert "sys.exit('licence server unreachable')" in evaluator.failure_summary()


def _nan_modulus_build(v):
    return build_cantilever({**v, "E": v["E"] * float("nan")})


def test_nan_never_reaches_opensees():
    m = OpenSeesModel(_nan_modulus_build, PARAMS, DOFS, n_modes=3, solver="-fullGenLapack")
    with pytest.raises(ModelEvaluationError, match=r"non_finite_input: ops.element got nan"):
        m.modal({})
    np.testing.assert_allclose(model().modal({}).frequencies_hz, model().modal({}).frequencies_hz)  # process intact
    assert type(ops.element).__name__ == "builtin_function_or_method"
