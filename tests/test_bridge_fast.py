"""Fast evaluation path of the bridge agrees with the plain OpenSees path."""

import pickle

import numpy as np
import pytest

from framework.core.correlation import mac_matrix, pair_modes
from framework.structures import bridge


@pytest.fixture(scope="module")
def models():
    fast = bridge.make_model(4, fast=True)
    return fast, fast.plain


def _paired(result, measured):
    pairing = pair_modes(
        result.frequencies_hz,
        measured.frequencies_hz,
        result.at(measured.dofs),
        measured.shapes,
        frequency_window=0.35,
    )
    idx = pairing.analytical_index
    return idx, result.frequencies_hz[idx], pairing.mac


def test_fast_and_plain_agree_on_random_points(models):
    fast, plain = models
    measured = bridge.measured()
    rng = np.random.default_rng(7)
    points = [{}] + [dict(zip(bridge.PARAMETER_NAMES, rng.uniform(0.6, 1.3, 6))) for _ in range(2)]
    for theta in points:
        rf, rp = fast.modal(theta), plain.modal(theta)
        assert rf.n_modes == rp.n_modes
        np.testing.assert_allclose(rf.frequencies_hz, rp.frequencies_hz, rtol=1e-6)
        idx_f, f_f, mac_f = _paired(rf, measured)
        idx_p, f_p, mac_p = _paired(rp, measured)
        np.testing.assert_array_equal(idx_f, idx_p)
        np.testing.assert_allclose(f_f, f_p, rtol=1e-4)
        np.testing.assert_allclose(mac_f, mac_p, atol=1e-4)
        diag = np.diag(mac_matrix(rf.shapes, rp.shapes))
        assert np.all(diag > 1 - 1e-6)
        np.testing.assert_array_equal(rf.mode_info["mode_type"], rp.mode_info["mode_type"])
        np.testing.assert_allclose(rf.mode_info["deck_energy"], rp.mode_info["deck_energy"], atol=1e-6)


def test_fast_model_pickles_without_its_operators(models):
    fast, _ = models
    fast.operators  # noqa: B018 - force extraction
    clone = pickle.loads(pickle.dumps(fast))
    assert clone._operators is None
    np.testing.assert_allclose(clone.modal({}).frequencies_hz, fast.modal({}).frequencies_hz, rtol=1e-9)


def _cable_state(fast, theta):
    from framework.models.base import full_theta
    from framework.models.opensees import ops_module, run_static
    from framework.structures.bridge import fast as bridge_fast

    op = fast.operators
    ops = ops_module()
    values = full_theta(fast.parameters, theta)
    ops.wipe()
    try:
        fast.plain.build(values)
        run_static(ops, fast.gravity)
        k3 = bridge_fast._current_cable_tangent(ops, op.__dict__, values)
    finally:
        ops.wipe()
    return values, k3


def test_symmetry_blocks_equal_full_solution(models):
    from framework.structures.bridge import fast as bridge_fast

    fast, _ = models
    op = fast.operators
    assert op.irreps is not None and len(op.irreps) == 4
    values, k3 = _cable_state(fast, {"T_Cab1": 1.2, "K_t_deck": 0.7})
    assert bridge_fast.is_symmetric_state(k3, op)
    w_max = (2 * np.pi * 15.0) ** 2
    w_sym, phi_sym = bridge_fast.solve_irreps(values, k3, op, w_max)
    w_full, phi_full = bridge_fast.solve_band(op.stiffness(values, k3), op.mass, w_max)
    np.testing.assert_allclose(w_sym, w_full, rtol=1e-9)
    # mass-normalized: phi' M phi = I in both
    np.testing.assert_allclose(np.einsum("ij,i,ij->j", phi_sym, op.mass, phi_sym), 1.0, rtol=1e-9)


def test_asymmetric_cable_state_uses_full_solution(models):
    from framework.structures.bridge import fast as bridge_fast

    fast, _ = models
    _, k3 = _cable_state(fast, {})
    k3 = k3.copy()
    k3[0] *= 1.001  # one cable element differs from its mirror images
    assert not bridge_fast.is_symmetric_state(k3, fast.operators)
