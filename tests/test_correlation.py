"""MAC, COMAC, MSF and pairing: hand-computed cases, properties, complex and degenerate inputs."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from framework.core.correlation import comac, frequency_errors, mac, mac_matrix, mac_paired, msf, pair_modes

finite = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False)
vec = arrays(np.float64, st.integers(2, 8), elements=finite).filter(lambda v: np.linalg.norm(v) > 1e-3)


def test_mac_hand_computed():
    # |[1,0].[1,1]|^2 / (1 * 2) = 0.5
    assert mac([1.0, 1.0], [1.0, 0.0]) == pytest.approx(0.5)
    assert mac([1.0, 2.0, 3.0], [2.0, 4.0, 6.0]) == pytest.approx(1.0)
    assert mac([1.0, 0.0], [0.0, 1.0]) == pytest.approx(0.0)
    # [1,2] vs [2,1]: (4)^2 / (5*5) = 16/25
    assert mac([1.0, 2.0], [2.0, 1.0]) == pytest.approx(16 / 25)


def test_msf_and_comac_hand_computed():
    phi_e = np.array([[1.0, 0.0], [2.0, 1.0]])
    phi_a = 2.0 * phi_e
    np.testing.assert_allclose(msf(phi_a, phi_e), [2.0, 2.0])
    np.testing.assert_allclose(comac(phi_a, phi_e), [1.0, 1.0])
    # DOF 1 of two modes: a = [1, 1], e = [1, -1] -> (|1|+|-1|)^2/(2*2) = 1 (COMAC ignores sign)
    a = np.array([[1.0, 1.0], [1.0, 0.0]])
    e = np.array([[1.0, -1.0], [0.0, 1.0]])
    np.testing.assert_allclose(comac(a, e)[0], 1.0)
    assert comac(a, e)[1] == pytest.approx(0.0)


def test_frequency_errors():
    np.testing.assert_allclose(frequency_errors([3.6, 5.0], [3.0, 5.0]), [0.2, 0.0])
    with pytest.raises(ValueError, match="measured frequencies must be finite and > 0"):
        frequency_errors([1.0], [0.0])


@settings(max_examples=60, deadline=None)
@given(vec, st.floats(-50, 50).filter(lambda s: abs(s) > 1e-3))
def test_mac_scale_invariant_and_bounded(v, scale):
    rng = np.random.default_rng(0)
    w = v + rng.normal(size=v.size)
    if np.linalg.norm(w) < 1e-6:
        return
    m = mac(v, w)
    assert 0.0 <= m <= 1.0
    assert mac(scale * v, w) == pytest.approx(m, rel=1e-9, abs=1e-12)
    assert mac(v, w) == pytest.approx(mac(w, v), rel=1e-12, abs=1e-12)  # symmetric
    assert mac(v, v) == pytest.approx(1.0)


@settings(max_examples=40, deadline=None)
@given(arrays(np.float64, (5, 3), elements=finite))
def test_mac_matrix_matches_pairwise(phi):
    if np.any(np.linalg.norm(phi, axis=0) < 1e-3):
        return
    M = mac_matrix(phi, phi)
    np.testing.assert_allclose(np.diag(M), 1.0, rtol=1e-9)
    np.testing.assert_allclose(M, M.T, atol=1e-12)
    np.testing.assert_allclose(mac_paired(phi, phi), 1.0, rtol=1e-9)


def test_complex_shapes():
    v = np.array([1.0 + 1j, 2.0 - 0.5j, 0.3j])
    assert mac(v * (0.3 - 2j), v) == pytest.approx(1.0)  # any complex scale
    assert msf(2j * v[:, None], v[:, None])[0] == pytest.approx(2j)


@pytest.mark.parametrize(
    "a, e, message",
    [
        ([0.0, 0.0], [1.0, 0.0], "zero norm"),
        ([np.nan, 1.0], [1.0, 0.0], "NaN or inf"),
        ([1.0, 0.0, 0.0], [1.0, 0.0], "phi_a has 3 DOFs but phi_e has 2"),
        (np.ones((2, 2, 2)), [1.0, 0.0], "expected a vector"),
        (["a", "b"], [1.0, 0.0], "must be numeric"),
        (np.empty((0, 1)), [1.0, 0.0], "empty"),
    ],
)
def test_degenerate_inputs_have_clear_errors(a, e, message):
    with pytest.raises(ValueError, match=message):
        mac_matrix(a, e)


def test_pairing_by_mac_reorders_and_reports_unmatched():
    phi_a = np.eye(3)
    phi_e = np.array([[0.0, 1.0, 0.6], [1.0, 0.0, 0.0], [0.0, 0.05, 0.8]])[:, [0, 1]]
    p = pair_modes([1.0, 2.0, 3.0], [2.1, 0.9], phi_a, phi_e)
    np.testing.assert_array_equal(p.analytical_index, [1, 0])
    assert p.matched.all()
    # a measured mode unlike any analytical one is unmatched (-1), never silently paired
    phi_e2 = np.array([[1.0, 0.577], [0.0, 0.577], [0.0, 0.577]])
    p2 = pair_modes([1.0, 2.0, 3.0], [1.0, 2.0], phi_a, phi_e2, mac_threshold=0.5)
    assert p2.analytical_index[0] == 0
    assert p2.analytical_index[1] == -1 and not p2.matched[1]
    assert list(p2.unmatched) == [1]


def test_pairing_frequency_window_and_order():
    phi = np.eye(2)
    p = pair_modes([1.0, 10.0], [1.0, 2.0], phi, phi, frequency_window=0.3)
    assert p.analytical_index[1] == -1  # its MAC partner is 400 % away in frequency
    q = pair_modes([1.0, 2.0, 3.0], [1.1, 2.2], method="order")
    np.testing.assert_array_equal(q.analytical_index, [0, 1])
    r = pair_modes([3.0, 1.0], [1.1, 2.9])  # no shapes: nearest frequency
    np.testing.assert_array_equal(r.analytical_index, [1, 0])


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 10_000), st.sampled_from(["mac", "frequency", "order"]),
       st.sampled_from([None, 0.2, 0.5]), st.floats(0.0, 0.95))
def test_batch_pairing_equals_single_pairing(seed, method, window, threshold):
    from framework.core.correlation import mac_matrix_batch, pair_modes_batch

    rng = np.random.default_rng(seed)
    n, n_dof, m_a, m_e = 6, 4, 4, 3
    fa = np.sort(rng.uniform(1, 10, (n, m_a)), axis=1)
    fe = np.sort(rng.uniform(1, 10, m_e))
    phi_a = rng.normal(size=(n, n_dof, m_a))
    phi_e = rng.normal(size=(n_dof, m_e))
    mm = mac_matrix_batch(phi_a, phi_e)
    idx, mac_b, matched = pair_modes_batch(fa, fe, mm, mac_threshold=threshold, frequency_window=window,
                                           method=method)
    for i in range(n):
        np.testing.assert_allclose(mm[i], mac_matrix(phi_a[i], phi_e), atol=1e-12)
        p = pair_modes(fa[i], fe, phi_a[i], phi_e, mac_threshold=threshold, frequency_window=window, method=method)
        np.testing.assert_array_equal(idx[i], p.analytical_index)
        np.testing.assert_array_equal(matched[i], p.matched)


def test_problem_batch_path_equals_single_path():
    from framework.structures.lab_frame.model import make_model, measured
    from framework.updating.objectives import ObjectiveSpec
    from framework.updating.problem import UpdatingProblem

    X = np.random.default_rng(5).random((50, 6))
    for spec in (ObjectiveSpec(), ObjectiveSpec(frequency_window=0.05, mac_threshold=0.99), ObjectiveSpec(beta=0)):
        p = UpdatingProblem(make_model(), measured(), objective=spec)
        batch = p.evaluate(X)
        single = np.array([p.objective1(x) for x in X])
        np.testing.assert_allclose(batch.objective, single, rtol=1e-12, atol=0)
