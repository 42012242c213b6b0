"""Matrix models, the shear building and the reference formulation on synthetic data."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse as sp

from framework.core.errors import InputError, ModelEvaluationError
from framework.core.parameters import Parameter, ParameterSet
from framework.measured.modes import MeasuredModes
from framework.models.base import ModalResult, safe_modal
from framework.models.matrix import LinearStiffness, MatrixModel, load_matrices, solve_condensation
from framework.models.shear_building import make_shear_building
from framework.updating.formulations.reference import (
    REFERENCE,
    normalize_at,
    reference_entries,
    reference_residuals,
)
from framework.updating.objectives import ObjectiveSpec
from framework.updating.problem import UpdatingProblem


def _params(n: int, lo: float = -0.5, hi: float = 0.5) -> ParameterSet:
    return ParameterSet(Parameter(f"alpha_{i + 1}", 0.0, lo, hi) for i in range(n))


def _chain(n: int, massless_every: int = 2, seed: int = 0):
    """Spring chain fixed at the ground: one K part per spring, every 2nd node massless."""
    rng = np.random.default_rng(seed)
    k = rng.uniform(1e3, 2e3, n)
    parts = []
    for i in range(n):
        e = np.zeros(n)
        e[i] = 1.0
        if i > 0:
            e[i - 1] = -1.0
        parts.append(sp.csc_matrix(k[i] * np.outer(e, e)))
    masses = np.where(np.arange(n) % massless_every == 1, 0.0, rng.uniform(1.0, 2.0, n))
    return parts, sp.diags(masses).tocsc(), k, masses


def test_linear_stiffness_matches_dense_sum():
    parts, _, _, _ = _chain(12)
    ks = LinearStiffness(parts)
    alpha = np.linspace(-0.4, 0.6, 12)
    expected = sum((1 + a) * p.toarray() for a, p in zip(alpha, parts))
    np.testing.assert_allclose(ks(alpha).toarray(), expected, rtol=1e-14, atol=1e-9)
    base = sp.identity(12, format="csc") * 5.0
    ks0 = LinearStiffness(parts, base=base)
    np.testing.assert_allclose(
        ks0(alpha).toarray(), 5.0 * np.eye(12) + sum(a * p.toarray() for a, p in zip(alpha, parts)), atol=1e-9
    )


def test_condensation_of_massless_node_is_exact():
    """m - k - (massless) - k - m chain, ground spring k: condensed series spring k/2.

    K_c = k [[1.5, -0.5], [-0.5, 0.5]], M = m I -> lambda = (k/m)(1 -+ sqrt(0.5)).
    """
    k, m = 1000.0, 2.0
    K = k * np.array([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]])
    M = np.diag([m, 0.0, m])
    lam, phi = solve_condensation(K, M, 2)
    np.testing.assert_allclose(lam, (k / m) * np.array([1 - math.sqrt(0.5), 1 + math.sqrt(0.5)]), rtol=1e-12)
    # massless DOF recovered from K_ss phi_s + K_sm phi_m = 0
    np.testing.assert_allclose(phi[1], (phi[0] + phi[2]) / 2.0, rtol=1e-12)


def test_shift_invert_agrees_with_condensation_for_singular_mass():
    parts, M, _, masses = _chain(60)
    assert (masses == 0).sum() == 30
    params = _params(60)
    dofs = {f"n{i}": i for i in (0, 10, 20, 58)}
    a = MatrixModel(parts, M, params, dofs, n_modes=6, solver="shift_invert")
    b = MatrixModel(parts, M, params, dofs, n_modes=6, solver="condensation")
    theta = {"alpha_3": 0.3, "alpha_40": -0.2}
    ra, rb = a.modal(theta), b.modal(theta)
    np.testing.assert_allclose(ra.frequencies_hz, rb.frequencies_hz, rtol=1e-9)
    for j in range(6):  # same shapes up to sign
        u, v = ra.shapes[:, j], rb.shapes[:, j]
        assert abs(u @ v) / (np.linalg.norm(u) * np.linalg.norm(v)) == pytest.approx(1.0, abs=1e-8)
    assert ra.mode_info["eigenvalue"] == pytest.approx((2 * math.pi * ra.frequencies_hz) ** 2, rel=1e-12)


def _ldl_pair(n: int = 60, **kwargs):
    parts, M, _, _ = _chain(n)
    params = _params(n, -0.9, 0.5)
    dofs = {f"n{i}": i for i in (0, 10, 20, n - 2)}
    a = MatrixModel(parts, M, params, dofs, n_modes=6, solver="shift_invert", **kwargs)
    b = MatrixModel(parts, M, params, dofs, n_modes=6, solver="shift_invert_ldl", **kwargs)
    return a, b


def test_reused_ldl_path_equals_shift_invert_at_many_points():
    pytest.importorskip("qdldl")
    a, b = _ldl_pair()
    rng = np.random.default_rng(3)
    for _ in range(5):  # one symbolic analysis, five numeric refactorizations
        theta = dict(zip(a.parameters.names, rng.uniform(-0.9, 0.5, 60)))
        (la_, pa), (lb, pb) = a.eigen(theta), b.eigen(theta)
        np.testing.assert_allclose(lb, la_, rtol=1e-10)
        cos = np.abs(np.sum(pa * (a.mass @ pb), 0))  # mass-normalized: |phi_a' M phi_b| = 1
        np.testing.assert_allclose(cos, 1.0, atol=1e-10)
    assert b.__dict__["_ldl"] is not None
    import pickle

    c = pickle.loads(pickle.dumps(b))  # the factorization is rebuilt in the receiving process
    assert "_ldl" not in c.__dict__
    np.testing.assert_array_equal(c.eigen(theta)[0], lb)


def test_reused_ldl_path_falls_back_on_an_indefinite_stiffness_and_without_qdldl(monkeypatch, caplog):
    pytest.importorskip("qdldl")
    from framework.models import repeated_eigen

    a, b = _ldl_pair()
    singular = {"alpha_1": -1.0}  # the ground spring removed: K singular (a mechanism), round-off pivot
    with pytest.raises(repeated_eigen.NotApplicable, match="not clearly positive definite"):
        b._reused_ldl().factor(b.stiffness_matrix(singular))
    np.testing.assert_array_equal(b.eigen(singular)[0], a.eigen(singular)[0])  # handed to today's path
    indefinite = b.stiffness(np.r_[-1.5, np.zeros(59)])  # a negative ground spring
    with pytest.raises(repeated_eigen.NotApplicable, match="not clearly positive definite"):
        b._reused_ldl().factor(indefinite)
    monkeypatch.setattr(repeated_eigen, "available", lambda: False)
    _, plain = _ldl_pair()
    with caplog.at_level("WARNING"):
        lam = plain.eigen({"alpha_2": 0.2})[0]
    assert "needs the optional package qdldl" in caplog.text
    np.testing.assert_array_equal(lam, a.eigen({"alpha_2": 0.2})[0])  # exactly today's path
    _, shifted = _ldl_pair(sigma=1.0)  # a nonzero shift: today's path
    np.testing.assert_allclose(shifted.eigen({})[0], a.eigen({})[0], rtol=1e-10)


def test_two_storey_shear_building_closed_form():
    """Equal m and k: omega^2 = (k/m)(3 -+ sqrt 5)/2; alpha_1 = 1 doubles storey 1."""
    m, k = 2.0, 800.0
    model = make_shear_building([m, m], [k, k])
    f = model.modal({}).frequencies_hz
    expected = np.sqrt((k / m) * np.array([(3 - math.sqrt(5)) / 2, (3 + math.sqrt(5)) / 2])) / (2 * math.pi)
    np.testing.assert_allclose(f, expected, rtol=1e-12)
    # k1 = 2k, k2 = k: det([[3k - w m, -k], [-k, k - w m]]) = 0 -> w m = k(2 -+ sqrt 2)
    f2 = model.modal({"alpha_1": 1.0}).frequencies_hz
    expected2 = np.sqrt((k / m) * np.array([2 - math.sqrt(2), 2 + math.sqrt(2)])) / (2 * math.pi)
    np.testing.assert_allclose(f2, expected2, rtol=1e-12)
    assert model.dofs == ("floor1", "floor2")
    assert model.parameters.names == ["alpha_1", "alpha_2"]


def test_collapsed_storey_is_a_recorded_failure():
    model = make_shear_building([1.0, 1.0], [10.0, 10.0])
    out = safe_modal(model, {"alpha_1": -1.0})
    assert isinstance(out, ModelEvaluationError)
    assert out.reason in ("singular_matrix", "indefinite_matrix")
    measured = MeasuredModes([0.3, 0.8], dofs=("floor1", "floor2"), shapes=np.eye(2) + 0.5)
    problem = UpdatingProblem(model, measured)
    x = problem.parameters.to_normalized(np.array([-1.0, 0.0]))
    assert problem.objective1(x) == pytest.approx(1e3)
    assert problem.evaluate(x[None, :]).reasons[0] in ("singular_matrix", "indefinite_matrix")


def test_matrix_model_input_errors_name_the_field():
    parts, M, _, _ = _chain(6)
    with pytest.raises(InputError, match="6 matrices for 5 parameters"):
        MatrixModel(parts, M, _params(5), {"a": 0})
    with pytest.raises(InputError, match="measured_dofs: index 9 outside 0..5"):
        MatrixModel(parts, M, _params(6), {"a": 9})
    with pytest.raises(InputError, match="solver must be"):
        MatrixModel(parts, M, _params(6), {"a": 0}, solver="lanczos")
    with pytest.raises(InputError, match=r"mass: shape \(5, 5\)"):
        MatrixModel(parts, np.eye(5), _params(6), {"a": 0})
    with pytest.raises(InputError, match="measured_floors"):
        make_shear_building([1, 1], [1, 1], measured_floors=[3])


def test_load_matrices_npz_and_missing_name(tmp_path):
    parts, M, _, _ = _chain(5)
    path = tmp_path / "model.npz"
    np.savez(path, K1=parts[0].toarray(), M=M.toarray(), dofs=np.array([1, 3]))
    data = load_matrices(path, ["K1", "M", "dofs"])
    assert sp.issparse(data["K1"]) and data["K1"].shape == (5, 5)
    np.testing.assert_array_equal(data["dofs"], [1, 3])
    with pytest.raises(InputError, match=r"missing matrix/matrices \['K9'\]"):
        load_matrices(path, ["K9"])
    with pytest.raises(InputError, match="matrix file not found"):
        load_matrices(tmp_path / "nope.mat", ["K"])


# ---- reference formulation ----------------------------------------------------------------
def _result(f, shapes, dofs=("a", "b", "c")):
    return ModalResult(np.asarray(f, float), np.asarray(shapes, float), dofs)


def test_reference_entries_and_normalization():
    psi = np.array([[0.2, -3.0], [1.0, 0.5], [-0.7, 1.0]])
    q = reference_entries(psi)
    np.testing.assert_array_equal(q, [1, 2])  # the exact 1 wins over a larger magnitude
    np.testing.assert_allclose(normalize_at(2 * psi, q)[q, [0, 1]], [1.0, 1.0])


def test_reference_residuals_by_hand():
    """Two modes, std weights: r_lambda = (lambda_e - lambda_a)/std_lambda, r_psi = w(1-sqrt MAC)/sqrt MAC."""
    psi = np.array([[1.0, 0.5], [0.5, 1.0], [0.1, -0.4]])
    std_psi = np.array([[0.0, 0.02], [0.03, 0.0], [0.04, 0.01]])
    f_e = np.array([2.0, 5.0])
    std_lambda = np.array([3.0, 20.0])
    lam_e = (2 * math.pi * f_e) ** 2
    measured = MeasuredModes(
        f_e,
        dofs=("a", "b", "c"),
        shapes=psi,
        frequency_std_hz=f_e * std_lambda / (2 * lam_e),
        shape_std=std_psi,
    )
    phi_a = psi + np.array([[0.0, 0.1], [0.2, 0.0], [0.0, 0.0]])
    f_a = np.array([2.1, 4.8])
    spec = ObjectiveSpec(formulation="reference")
    r, corr = reference_residuals(_result(f_a, phi_a), measured, spec)
    lam_a = (2 * math.pi * f_a) ** 2
    np.testing.assert_allclose(r[:2], (lam_e - lam_a) / std_lambda, rtol=1e-10)
    macs = [(psi[:, i] @ phi_a[:, i]) ** 2 / (psi[:, i] @ psi[:, i]) / (phi_a[:, i] @ phi_a[:, i]) for i in range(2)]
    w_psi = [1 / math.hypot(0.03, 0.04), 1 / math.hypot(0.02, 0.01)]  # entry q_i dropped
    expected = [w * (1 - math.sqrt(m)) / math.sqrt(m) for w, m in zip(w_psi, macs)]
    np.testing.assert_allclose(r[2:], expected, rtol=1e-10)
    np.testing.assert_allclose(corr.mac, macs, rtol=1e-12)
    # unit weights: relative eigenvalue error
    r_unit, _ = reference_residuals(_result(f_a, phi_a), measured, ObjectiveSpec(options={"weights": "unit"}))
    np.testing.assert_allclose(r_unit[:2], (lam_e - lam_a) / lam_e, rtol=1e-12)
    np.testing.assert_allclose(REFERENCE.split(r, measured, spec), [np.sum(r[:2] ** 2), np.sum(r[2:] ** 2)])


def test_reference_forced_versus_mac_matching_on_swapped_modes():
    psi = np.array([[1.0, 0.0], [0.0, 1.0], [0.5, -0.5]])
    measured = MeasuredModes([2.0, 3.0], dofs=("a", "b", "c"), shapes=psi)
    swapped = _result([2.0, 3.0], psi[:, ::-1])
    r_order, corr_order = reference_residuals(swapped, measured, ObjectiveSpec(options={"matching": "order"}))
    assert corr_order.matched.all()
    assert corr_order.mac[0] == pytest.approx((0.5 * -0.5) ** 2 / 1.25**2)
    assert np.sum(r_order**2) > 1.0
    near = psi[:, 1] + np.array([0.3, 0.0, 0.0])  # right frequency, wrong-ish shape
    three = _result([2.0, 2.0, 3.0], np.column_stack([psi[:, 1], psi[:, 0], near]))
    r_mac, corr_mac = reference_residuals(three, measured, ObjectiveSpec(options={"matching": "mac"}))
    np.testing.assert_array_equal(corr_mac.analytical_index, [1, 0])  # highest MAC, not nearest frequency
    assert np.sum(r_mac[:2] ** 2) == pytest.approx((5 / 9) ** 2)  # mode 2 (3 Hz) paired at 2 Hz: (9 - 4)/9
    assert np.sum(r_mac[2:] ** 2) == pytest.approx(0.0, abs=1e-20)


def test_reference_options_are_validated():
    model = make_shear_building([1.0], [100.0])
    measured = MeasuredModes([1.5], dofs=("floor1",), shapes=np.ones((1, 1)))
    with pytest.raises(InputError, match="objective.options: matching must be one of"):
        UpdatingProblem(model, measured, objective=ObjectiveSpec(formulation="reference", options={"matching": "x"}))
    with pytest.raises(InputError, match=r"unknown key\(s\) \['weight'\]"):
        UpdatingProblem(model, measured, objective=ObjectiveSpec(formulation="reference", options={"weight": "std"}))


def test_from_file_builds_the_model_a_config_names(tmp_path):
    from framework.models.matrix import from_file

    parts, M, _, _ = _chain(8)
    path = tmp_path / "chain.npz"
    np.savez(path, **{f"K{j}": p.toarray() for j, p in enumerate(parts)}, M=M.toarray(), meas=np.array([1, 5, 7]))
    model = from_file(str(path), [f"K{j}" for j in range(8)], "M", "meas", bounds=(-0.3, 0.3), n_modes=2)
    assert model.dofs == ("dof1", "dof5", "dof7")
    np.testing.assert_array_equal(model.dof_index, [0, 4, 6])
    assert model.parameters.names[-1] == "alpha_8" and model.parameters.upper[0] == 0.3
    direct = MatrixModel(parts, M, _params(8), {"a": 0}, n_modes=2)
    np.testing.assert_allclose(model.modal({}).frequencies_hz, direct.modal({}).frequencies_hz, rtol=1e-12)
    with pytest.raises(InputError, match="bounds: expected one"):
        from_file(str(path), ["K0", "K1"], "M", [1], bounds=[(0, 1), (0, 1), (0, 1)])
