"""Derivatives of eigenvalues and mass-normalized eigenvectors with respect to model parameters.

For K phi_i = lambda_i M phi_i with phi_i' M phi_i = 1 and a simple eigenvalue lambda_i,
the derivative with respect to a parameter theta_j is (dK = dK/dtheta_j, dM = dM/dtheta_j)

    dlambda_i = phi_i' (dK - lambda_i dM) phi_i

and the eigenvector derivative solves (K - lambda_i M) dphi_i = -(dK - lambda_i dM - dlambda_i M) phi_i,
a singular system (its null space is phi_i), fixed by the derivative of the normalization,
phi_i' M dphi_i = -1/2 phi_i' dM phi_i. Nelson's method (Nelson 1976) solves it exactly:
with p the entry of largest |phi_i|, set v_p = 0 (row and column p of K - lambda_i M
replaced by those of the identity, right-hand side 0 at p), solve the now regular system
for v, and add the null-space part: dphi_i = v + c phi_i, c = -phi_i' M v - 1/2 phi_i' dM phi_i.
The reduced matrix is regular whenever lambda_i is simple and phi_i(p) != 0, also for a
singular M (massless DOFs): an infinite eigenvalue adds no null vector to K - lambda_i M.
Normalization convention: the derivative keeps phi' M phi = 1 and is that of the eigenvector
with the sign the eigen solver returned (a continuous branch through the point).

One factorization of an n x n matrix per differentiated mode (dense LU up to
``DENSE_LIMIT`` DOFs, SuperLU above, with threshold pivoting in symmetric mode), one block
solve with a right-hand side per parameter.

Repeated or close eigenvalues: the derivative of a repeated eigenvalue's eigenvectors is not
defined by this formula (and Nelson's reduced matrix becomes singular as the gap closes), so
a differentiated mode whose relative gap to any other computed eigenvalue is below
``CLOSE_EIGENVALUE_RTOL`` raises :class:`CloseEigenvalues` and the caller falls back to
finite differences. Only the computed modes are checked: a model that computes n modes
cannot see the (n+1)-th.

Cost in eigen-solve equivalents (deterministic, never a timing): every factorization of a
matrix of the model's size and every re-assembly of the model's matrices at a shifted
parameter value counts as one eigen solution. One eigen solution of the model contains at
least one factorization of that size (shift-invert) or a dense decomposition of the same
matrix, and one model evaluation contains its assembly, so the count never understates the
work (measured ratios are printed by benchmarks/bench_jacobian.py).

Written here because scipy has no eigenvector-derivative routine; the method is textbook.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as spla

log = logging.getLogger(__name__)

#: relative eigenvalue gap below which a mode counts as repeated / close (no exact derivative)
CLOSE_EIGENVALUE_RTOL = 1e-6
#: up to this many DOFs the systems of Nelson's method are solved densely
DENSE_LIMIT = 200


class CloseEigenvalues(Exception):
    """A differentiated mode has a repeated or close eigenvalue: use finite differences."""


@dataclass(frozen=True)
class ModalDerivatives:
    """Derivatives of the modes ``modes`` (indices into the ModalResult's modes).

    dlambda (m, k): d lambda / d theta (rad^2/s^2 per unit of each parameter); dphi
    (n_dof, m, k): d phi / d theta of the mass-normalized shapes at the model's DOFs (the
    rows of ``ModalResult.shapes``); parameters: the k parameter names in column order;
    cost: eigen-solve equivalents spent (see the module docstring).
    """

    modes: np.ndarray
    parameters: tuple[str, ...]
    dlambda: np.ndarray
    dphi: np.ndarray
    cost: int

    def position(self, mode: int) -> int:
        """Row of ``mode`` (an index into the ModalResult's modes) in dlambda / dphi."""
        hits = np.flatnonzero(self.modes == mode)
        if hits.size == 0:
            raise KeyError(f"no derivatives of mode {mode}; have {self.modes.tolist()}")
        return int(hits[0])


def check_separated(eigenvalues: np.ndarray, modes: Sequence[int], rtol: float = CLOSE_EIGENVALUE_RTOL) -> None:
    """Raise CloseEigenvalues if a mode in ``modes`` has a relative gap < rtol to any other eigenvalue."""
    lam = np.asarray(eigenvalues, float)
    for i in modes:
        others = np.delete(np.arange(lam.size), i)
        if others.size == 0:
            continue
        gaps = np.abs(lam[others] - lam[i])
        j = int(np.argmin(gaps))
        rel = gaps[j] / max(abs(lam[i]), np.finfo(float).tiny)
        if rel < rtol:
            raise CloseEigenvalues(
                f"modes {i + 1} and {others[j] + 1} have close eigenvalues {lam[i]:.10g} and {lam[others[j]]:.10g} "
                f"(relative gap {rel:.2e} < {rtol:g})"
            )


def normalize_mass(M, phi: np.ndarray) -> np.ndarray:
    """phi scaled to phi' M phi = 1 per column (removes solver round-off in the normalization)."""
    norms = np.sqrt(np.einsum("ij,ij->j", phi, np.asarray(M @ phi)))
    return phi / norms


def eigen_derivatives(K, M, lam: np.ndarray, phi: np.ndarray, dK_phi: np.ndarray, dM_phi: np.ndarray | None = None):
    """Eigenvalue and eigenvector derivatives of the modes phi (n, m) by Nelson's method.

    K, M: (n, n) dense or sparse (M may be singular); lam (m,); phi (n, m) mass-normalized;
    dK_phi (n, m, k): dK_j phi_i; dM_phi: dM_j phi_i (None: M does not depend on the
    parameters). Returns dlambda (m, k), dphi (n, m, k) and the number of factorizations.
    """
    n, m = phi.shape
    k = dK_phi.shape[2]
    dense = not sp.issparse(K) or n <= DENSE_LIMIT
    if dense:
        K = K.toarray() if sp.issparse(K) else np.asarray(K, float)
        M = M.toarray() if sp.issparse(M) else np.asarray(M, float)
    else:
        K, M = sp.csc_matrix(K), sp.csc_matrix(M)
    Mphi = np.asarray(M @ phi)
    dlam = np.einsum("ni,nij->ij", phi, dK_phi)
    if dM_phi is not None:
        dlam -= lam[:, None] * np.einsum("ni,nij->ij", phi, dM_phi)
    dphi = np.empty((n, m, k))
    for i in range(m):
        rhs = -dK_phi[:, i, :] + dlam[i][None, :] * Mphi[:, i : i + 1]
        if dM_phi is not None:
            rhs += lam[i] * dM_phi[:, i, :]
        p = int(np.argmax(np.abs(phi[:, i])))
        rhs[p, :] = 0.0
        v = _solve_reduced(K - lam[i] * M, p, rhs, dense)
        c = -(Mphi[:, i] @ v)
        if dM_phi is not None:
            c -= 0.5 * np.einsum("n,nj->j", phi[:, i], dM_phi[:, i, :])
        dphi[:, i, :] = v + phi[:, i : i + 1] * c[None, :]
    return dlam, dphi, m


def _solve_reduced(A, p: int, rhs: np.ndarray, dense: bool) -> np.ndarray:
    """Solve A v = rhs with v_p = 0: row and column p of A replaced by those of the identity."""
    if dense:
        A = np.array(A, dtype=float)
        A[p, :] = 0.0
        A[:, p] = 0.0
        A[p, p] = 1.0
        return la.lu_solve(la.lu_factor(A, check_finite=False), rhs, check_finite=False)
    A = sp.csc_matrix(A, copy=True)
    A.sum_duplicates()
    A.data[A.indices == p] = 0.0  # row p
    A.data[A.indptr[p] : A.indptr[p + 1]] = 0.0  # column p
    diagonal = A.indptr[p] + np.flatnonzero(A.indices[A.indptr[p] : A.indptr[p + 1]] == p)
    if diagonal.size:
        A.data[diagonal[0]] = 1.0
    else:
        A = (A + sp.csc_matrix(([1.0], ([p], [p])), shape=A.shape)).tocsc()
    order = _ordering(A)
    lu = spla.splu(A[order][:, order].tocsc(), permc_spec="NATURAL", diag_pivot_thresh=0.1,
                   options={"SymmetricMode": True})
    v = np.empty_like(rhs)
    v[order] = lu.solve(rhs[order])
    return v


#: fill-reducing symmetric permutation per sparsity pattern (shape, nnz, hashes of the pattern)
_ORDERINGS: dict[tuple, np.ndarray] = {}


def _ordering(A: sp.csc_matrix) -> np.ndarray:
    """Symmetric permutation q of A (factorize A[q][:, q] in natural order): SuperLU's minimum
    degree ordering on A' + A, computed once per sparsity pattern and process and reused, since
    every differentiated mode and every point has the same pattern (saves the ordering step,
    about a quarter of a factorization; same fill)."""
    key = (A.shape, A.nnz, hash(A.indptr.tobytes()), hash(A.indices.tobytes()))
    if key not in _ORDERINGS:
        lu = spla.splu(A, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.1, options={"SymmetricMode": True})
        if len(_ORDERINGS) > 64:
            _ORDERINGS.clear()
        _ORDERINGS[key] = np.argsort(lu.perm_c)
    return _ORDERINGS[key]
