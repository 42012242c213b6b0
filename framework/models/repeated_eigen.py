"""Repeated eigen solutions on one sparsity pattern: shift-invert Lanczos on a reused LDL' (ours).

A matrix model solves K(alpha) phi = lambda M phi for thousands of alpha with one sparsity
pattern of K. Today's path (:func:`framework.models.matrix.solve_shift_invert`) lets
``eigsh`` factorize K - sigma M from scratch each time (SuperLU: column ordering, symbolic
and numeric LU) and runs ARPACK's shift-invert Lanczos with 20 vectors. Here:

- :class:`ReusedLDL`: K = P L D L' P' by QDLDL (the ``qdldl`` package, optional extra
  ``fast``): the fill-reducing ordering P (AMD) and the elimination tree are computed once per
  pattern; each new K is only a numeric refactorization (``update``) of its upper triangle,
  whose entries are gathered from K's data by an index map built once;
- positive definiteness is certified by the factorization itself: with a symmetric
  permutation and no pivoting, K is positive definite iff every d_i > 0 (Sylvester's law of
  inertia); a pivot at or below ``PIVOT_RTOL`` times its diagonal entry of K is a singular
  K up to round-off (a mechanism). Anything else than clearly positive pivots (an indefinite
  or nearly singular K, a failed factorization) raises :class:`NotApplicable` and the caller
  falls back to today's path, which returns its modes or raises the usual evaluation errors;
- the same shift-invert Lanczos (ARPACK ``eigsh``, shift 0, fixed start vector (1, ..., 1),
  tolerance 0 = machine precision) with the operator K^-1 given by the factorization and
  ``ncv`` = max(2 k + 1, 15) Lanczos vectors instead of 20 (fewer solves per restart cycle).

Equal accuracy: benchmarks/bench_repeated_eigen.py prints the largest relative frequency
difference and 1 - MAC against today's path next to the measured speed-up. The result is a
function of K alone (ordering from the pattern, fixed start vector), identical in every
process. Without ``qdldl`` the model uses today's path (a warning once per process).

Why QDLDL and not CHOLMOD (scikit-sparse): scikit-sparse has no wheel and needs the
SuiteSparse headers; QDLDL ships wheels and does exactly the reuse needed (symbolic once,
numeric per K). scipy's SuperLU cannot reuse a symbolic factorization.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

#: d_i / K_ii (permuted) at or below which the LDL' path hands the solve to today's path
PIVOT_RTOL = 1e-10


class NotApplicable(Exception):
    """The fast path cannot certify this solve (K not positive definite, factorization failed)."""


def available() -> bool:
    """True when the optional ``qdldl`` package is installed."""
    try:
        import qdldl  # noqa: F401
    except ImportError:
        return False
    return True


class ReusedLDL:
    """LDL' factorizations of many K with the sparsity pattern of ``pattern`` (CSC, sorted indices).

    The symbolic analysis is done once from ``pattern``; :meth:`factor` refactorizes for the
    values of a K with the same indices/indptr.
    """

    def __init__(self, pattern: sp.csc_matrix):
        import qdldl

        pattern = sp.csc_matrix(pattern)
        self.n = pattern.shape[0]
        self.nnz = pattern.nnz
        self._indptr = pattern.indptr.copy()
        self._indices = pattern.indices.copy()
        cols = np.repeat(np.arange(self.n), np.diff(pattern.indptr))
        self._upper = np.flatnonzero(pattern.indices <= cols)  # entries (i, j) with i <= j, in CSC order
        upper_counts = np.bincount(cols[self._upper], minlength=self.n)
        self._upper_indptr = np.concatenate([[0], np.cumsum(upper_counts)])
        self._upper_indices = pattern.indices[self._upper]
        self._solver = qdldl.Solver(self._upper_matrix(pattern.data), upper=True)
        self._order = np.asarray(self._solver.factors()[2], dtype=np.int64)  # fixed by the pattern
        self._diagonal = np.flatnonzero(pattern.indices == cols)  # positions of K_ii in K.data

    def _upper_matrix(self, data: np.ndarray) -> sp.csc_matrix:
        return sp.csc_matrix((np.asarray(data, dtype=float)[self._upper], self._upper_indices, self._upper_indptr),
                             shape=(self.n, self.n))

    def factor(self, stiffness: sp.csc_matrix):
        """Factorize K (same indices/indptr as the pattern); returns the solve function x -> K^-1 x."""
        if (stiffness.nnz != self.nnz or not np.array_equal(stiffness.indptr, self._indptr)
                or not np.array_equal(stiffness.indices, self._indices)):
            raise NotApplicable("stiffness does not have the factorization's sparsity pattern")
        try:
            self._solver.update(self._upper_matrix(stiffness.data), upper=True)
            d = np.asarray(self._solver.factors()[1])
        except Exception as exc:  # a zero pivot: K singular
            raise NotApplicable(f"LDL': {exc}") from None
        diagonal = np.zeros(self.n)
        diagonal[self._indices[self._diagonal]] = stiffness.data[self._diagonal]
        if not (np.all(np.isfinite(d)) and np.all(d > PIVOT_RTOL * np.abs(diagonal[self._order]))):
            raise NotApplicable("K is not clearly positive definite (LDL' pivots)")
        return self._solver.solve


def lowest_modes(stiffness: sp.csc_matrix, mass, n_modes: int, ldl: ReusedLDL) -> tuple[np.ndarray, np.ndarray]:
    """Lowest ``n_modes`` eigenpairs (lambda ascending, phi (n, n_modes)) of K phi = lambda M phi,
    shift-invert Lanczos at shift 0 with K^-1 from ``ldl``. Raises NotApplicable (use today's path)."""
    n = stiffness.shape[0]
    solve = ldl.factor(stiffness)
    op = spla.LinearOperator((n, n), matvec=solve, dtype=float)
    ncv = min(n, max(2 * n_modes + 1, 15))
    try:
        lam, phi = spla.eigsh(stiffness, k=n_modes, M=mass, sigma=0.0, OPinv=op, v0=np.ones(n), tol=0.0,
                              ncv=ncv, which="LM")
    except spla.ArpackNoConvergence:
        raise NotApplicable("ARPACK did not converge") from None
    order = np.argsort(lam)
    lam, phi = lam[order], phi[:, order]
    if not (np.all(np.isfinite(lam)) and np.all(lam > 0.0)):
        raise NotApplicable("non-positive eigenvalue")
    return lam, phi
