"""Lowest modes of K phi = omega^2 M phi from assembled matrices, a deterministic function of K and M.

- up to :data:`DENSE_LIMIT` equations (dense, :func:`condensed_modes`): exact
  static condensation of the massless DOFs s (zero rows of M),
  K_c = K_mm - K_ms K_ss^-1 K_sm, phi_s = -K_ss^-1 K_sm phi_m (both from one Cholesky
  factorization of K with the massless DOFs first), then the LARGEST eigenvalues
  mu = 1 / omega^2 of (U_mm^-T M_mm U_mm^-1) y = mu y with K_c = U_mm' U_mm, phi_m = U_mm^-1 y
  (dense LAPACK eigh, subset by index); M_mm may be singular (e.g. a point mass on a rigid
  link gives its master rotations a mass block of rank 2);
- above, when few modes are asked (2 k + 1 < DOFs with mass and k < 10 % of them):
  shift-invert Lanczos on (K - 0 M)^-1 M with the fixed start vector (1, ..., 1)
  (:func:`framework.models.matrix.solve_shift_invert`); massless DOFs need no treatment
  there (their infinite eigenvalues map to 0 and are never returned).

Why not eigh(K_c, M_mm) (:func:`framework.models.matrix.solve_condensation`): LAPACK gets the
smallest eigenvalues of M^-1/2 K_c M^-1/2 with an absolute error ~eps x its norm, i.e. a
relative error eps x omega_max^2 / omega_1^2; with stiff springs and light nodes (the
detailed lab frame: ~1e8) that is 2e-9 in omega_1^2, and it needs M_mm positive definite.
The largest eigenvalues mu carry a relative error ~eps instead; measured against an
extended-precision Rayleigh-quotient iteration on the lab frame (omega_1^2): 3e-11 (this
module), 4e-11 (shift-invert), 4e-10 (OpenSees' -fullGenLapack), 2e-9 (eigh(K_c, M_mm)).

Both paths run with BLAS limited to one thread, so equal matrices give bit-identical modes
in any process, whatever ran before (unlike ARPACK started from its internal random
vector). Shapes are mass-normalized, phi' M phi = 1; :func:`sign_rule` fixes each mode's sign.
Failures: a mechanism (K singular, e.g. an unsupported structure) has rigid-body
eigenvalues at round-off level, ~1e-16 of max_i(K_ii / M_ii) over the DOFs with mass; any
|omega_1^2| <= :data:`MECHANISM_RTOL` x that scale is "singular_matrix" (also a singular
stiffness of the massless DOFs), a lower one "indefinite_matrix" (a buckled or unstable
state), whether the Cholesky factorization of K failed or passed on round-off pivots.
"""

from __future__ import annotations

import contextlib

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from framework.core.errors import ModelEvaluationError
from framework.models.matrix import solve_shift_invert

#: Up to this many equations the dense solver is used (above: shift-invert when few modes are asked).
DENSE_LIMIT = 2000

#: omega^2 / max(K_ii / M_ii) at or below which the lowest mode is a mechanism.
MECHANISM_RTOL = 1e-12

_CONTROLLER: list = []


def single_thread_blas():
    """Context limiting BLAS to one thread (threadpoolctl, if installed).

    The dense solves are small; on a shared machine multi-threaded OpenBLAS is slower, and
    one thread makes the rounding independent of the thread count of the process.
    """
    if not _CONTROLLER:
        try:
            from threadpoolctl import ThreadpoolController

            _CONTROLLER.append(ThreadpoolController())
        except ImportError:  # pragma: no cover - optional
            _CONTROLLER.append(None)
    if _CONTROLLER[0] is None:  # pragma: no cover
        return contextlib.nullcontext()
    return _CONTROLLER[0].limit(limits=1, user_api="blas")


def lowest_modes(stiffness: np.ndarray, mass: np.ndarray, n_modes: int) -> tuple[np.ndarray, np.ndarray]:
    """(omega^2 (n_modes,) ascending in rad^2/s^2, phi (n, n_modes) with phi' M phi = 1).

    Raises ModelEvaluationError: "eigen_failed" (non-finite matrices, mass not positive
    definite on its DOFs), "too_few_modes", "indefinite_matrix", "singular_matrix".
    """
    k = np.asarray(stiffness, dtype=float)
    m = np.asarray(mass, dtype=float)
    if not (np.all(np.isfinite(k)) and np.all(np.isfinite(m))):
        raise ModelEvaluationError("eigen_failed", "non-finite entries in the assembled stiffness or mass")
    n = k.shape[0]
    massive = np.any(m != 0.0, axis=1)
    n_mass = int(massive.sum())
    if n_modes > n_mass:
        raise ModelEvaluationError("too_few_modes", f"n_modes={n_modes} > {n_mass} DOFs with mass")
    with single_thread_blas():
        if n > DENSE_LIMIT and max(2 * n_modes + 1, 20) < n_mass and n_modes < 0.1 * n_mass:
            k_sym = 0.5 * (k + k.T)  # OpenSees' assembled tangent is symmetric up to round-off
            omega2, phi = solve_shift_invert(sp.csc_matrix(k_sym), sp.csc_matrix(m), n_modes)
        else:
            omega2, phi = condensed_modes(k, m, n_modes)  # reads the upper triangle of K only
        phi = phi / np.sqrt(np.einsum("ij,ij->j", phi, m @ phi))
    scale = _omega2_scale(np.diag(k)[massive], np.diag(m)[massive])
    if omega2[0] <= MECHANISM_RTOL * scale:
        raise ModelEvaluationError(
            "singular_matrix", f"mechanism: lowest omega^2 {omega2[0]:.3g} <= {MECHANISM_RTOL:g} x {scale:.3g}"
        )
    return omega2, phi


def condensed_modes(k: np.ndarray, m: np.ndarray, n_modes: int) -> tuple[np.ndarray, np.ndarray]:
    """Lowest modes by condensation of the massless DOFs and the inverse problem M_mm phi = mu K_c phi (dense).

    k (n, n) symmetric (up to round-off: one triangle is read), m (n, n) with zero rows at
    massless DOFs. One Cholesky factorization of K with the massless DOFs s first,
    K = U' U, U = [[U_ss, U_sm], [0, U_mm]], gives
    K_c = U_mm' U_mm and K_ss^-1 K_sm = U_ss^-1 U_sm. Returns (omega^2 ascending, phi (n, n_modes)).
    """
    massive = np.any(m != 0.0, axis=1)
    mi, si = np.flatnonzero(massive), np.flatnonzero(~massive)
    ns = si.size
    order = np.concatenate([si, mi])
    try:
        upper = sla.cholesky(k[np.ix_(order, order)], lower=False, check_finite=False)
    except np.linalg.LinAlgError:
        raise _not_positive_definite(k, si, mi, m[np.ix_(mi, mi)]) from None
    u_mm = upper[ns:, ns:]
    # A = U_mm^-T M_mm U_mm^-1: the eigenvalues of A y = mu y are mu = 1 / omega^2, phi_m = U_mm^-1 y
    x = sla.solve_triangular(u_mm, m[np.ix_(mi, mi)], trans="T", check_finite=False)
    a = sla.solve_triangular(u_mm, x.T, trans="T", check_finite=False)
    a = 0.5 * (a + a.T)
    mu, y = sla.eigh(a, subset_by_index=[mi.size - n_modes, mi.size - 1], check_finite=False)
    mu, y = mu[::-1], y[:, ::-1]
    if not mu[-1] > mi.size * np.finfo(float).eps * mu[0]:
        raise ModelEvaluationError("too_few_modes", f"the mass matrix has rank < n_modes={n_modes}")
    phi_m = sla.solve_triangular(u_mm, y, check_finite=False)
    phi = np.empty((k.shape[0], n_modes))
    phi[mi] = phi_m
    phi[si] = -sla.solve_triangular(upper[:ns, :ns], upper[:ns, ns:] @ phi_m, check_finite=False)
    return 1.0 / mu, phi


def _omega2_scale(diag_k: np.ndarray, diag_m: np.ndarray) -> float:
    """max_i K_ii / M_ii over DOFs with a positive diagonal mass (an estimate of omega_max^2; K before
    condensation: a mechanism's condensed stiffness is zero up to round-off)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return float(np.max(np.where(diag_m > 0.0, diag_k / diag_m, 0.0), initial=0.0))


def _not_positive_definite(k: np.ndarray, si: np.ndarray, mi: np.ndarray, m_mm: np.ndarray) -> ModelEvaluationError:
    """The error for a stiffness that failed Cholesky: "singular_matrix" if its massless block does
    or the condensed K_c has a round-off-level lowest eigenvalue (a mechanism), else "indefinite_matrix"."""
    scale = _omega2_scale(np.diag(k)[mi], np.diag(m_mm))
    k_c = k[np.ix_(mi, mi)]
    if si.size:
        k_sm = k[np.ix_(si, mi)]
        try:
            factor = sla.cho_factor(k[np.ix_(si, si)], check_finite=False)
        except np.linalg.LinAlgError as exc:
            return ModelEvaluationError("singular_matrix", f"stiffness of the massless DOFs: {exc}")
        k_c = k_c - k_sm.T @ sla.cho_solve(factor, k_sm, check_finite=False)
    try:
        lowest = float(sla.eigh(0.5 * (k_c + k_c.T), m_mm, eigvals_only=True, subset_by_index=[0, 0],
                                check_finite=False)[0])
    except (np.linalg.LinAlgError, ValueError) as exc:
        return ModelEvaluationError("eigen_failed", f"stiffness not positive definite: {exc}")
    if lowest < -MECHANISM_RTOL * scale:
        return ModelEvaluationError("indefinite_matrix", f"negative eigenvalue {lowest:.4g}")
    return ModelEvaluationError("singular_matrix", f"mechanism: lowest omega^2 {lowest:.3g} (scale {scale:.3g})")


def sign_rule(measured: np.ndarray, full: np.ndarray) -> np.ndarray:
    """Signs (+1/-1 per mode) making each mode's largest-magnitude measured component positive.

    measured: (n_dofs, k) shapes at the measured DOFs; full: (n, k) the equation-space
    shapes, used when every measured component of a mode is zero. Ties: the first DOF.
    """
    measured = np.asarray(measured, dtype=float).reshape(-1, full.shape[1])
    signs = np.ones(full.shape[1])
    for j in range(full.shape[1]):
        column = measured[:, j] if measured.size and np.any(measured[:, j] != 0.0) else full[:, j]
        if column.size and column[np.argmax(np.abs(column))] < 0.0:
            signs[j] = -1.0
    return signs
