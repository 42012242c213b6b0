"""Matrix models: structures given directly by stiffness and mass matrices.

The stiffness is linear in the updating parameters alpha_j,

    K(alpha) = K_0 + sum_j alpha_j K_j,

where K_0 defaults to sum_j K_j, i.e. K = sum_j (1 + alpha_j) K_j (substructure scaling).
The mass M is fixed and may be singular (massless DOFs, e.g. rotations of a frame model
with lumped translational masses). Modes solve K phi = omega^2 M phi, f = omega / 2 pi:

- ``solver="shift_invert"`` (sparse): ARPACK Lanczos on (K - sigma M)^-1 M
  (scipy.sparse.linalg.eigsh with ``sigma``); infinite eigenvalues of massless DOFs map
  to 0 there and are never returned, so a singular M needs no special treatment;
- ``solver="condensation"`` (dense): exact static condensation of the massless DOFs s,
  K_c = K_mm - K_ms K_ss^-1 K_sm, then eigh(K_c, M_mm); shapes at s are recovered as
  phi_s = -K_ss^-1 K_sm phi_m;
- ``solver="auto"``: condensation up to ``DENSE_LIMIT`` DOFs, shift-invert above;
- ``solver="shift_invert_ldl"`` (ours, for repeated solves): the same shift-invert Lanczos at
  shift 0 with K^-1 from an LDL' factorization whose symbolic analysis is done once per model
  and process (:mod:`framework.models.repeated_eigen`, optional package ``qdldl``); falls back
  to "shift_invert" for a K that is not positive definite, a nonzero ``sigma`` or without
  ``qdldl``.

Measured DOFs are given by 0-based index with a label each. The model is picklable and
stateless between calls (the matrices are read-only inputs).

Exact modal derivatives (:meth:`MatrixModel.modal_derivatives`, for exact Jacobians):
dK/dalpha_j = K_j, dM = 0, Nelson's method on the full (n_dof) problem with the full
eigenvectors kept in ``ModalResult.meta["eigenvectors"]`` (see :mod:`framework.core.modal_derivatives`).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp

from framework.core.errors import InputError, ModelEvaluationError
from framework.core.modal_derivatives import (
    CLOSE_EIGENVALUE_RTOL,
    ModalDerivatives,
    check_separated,
    eigen_derivatives,
    normalize_mass,
)
from framework.core.parameters import ParameterSet
from framework.models.base import ModalResult, full_theta, safe_modal

log = logging.getLogger(__name__)

#: Up to this many DOFs the dense condensation solver is used by ``solver="auto"``.
DENSE_LIMIT = 200

#: Eigen solvers of a MatrixModel (module docstring).
SOLVERS = ("auto", "shift_invert", "condensation", "shift_invert_ldl")


def _as_csc(matrix, where: str) -> sp.csc_matrix:
    try:
        out = sp.csc_matrix(matrix, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{where}: not a numeric matrix: {exc}") from exc
    if out.shape[0] != out.shape[1]:
        raise InputError(f"{where}: matrix must be square, got shape {out.shape}")
    if out.nnz and not np.all(np.isfinite(out.data)):
        raise InputError(f"{where}: matrix has non-finite entries")
    return out


class LinearStiffness:
    """K(alpha) = K_0 + sum_j alpha_j K_j on one shared sparsity pattern.

    All matrices are put on the union pattern once, so K(alpha) is a single product
    ``data = d_0 + D alpha`` (D of shape (nnz, J)) instead of a sum of sparse matrices.
    """

    def __init__(self, parts: Sequence, base=None):
        if not parts:
            raise InputError("stiffness_parts: at least one stiffness matrix is required")
        mats = [_as_csc(p, f"stiffness_parts[{j}]") for j, p in enumerate(parts)]
        n = mats[0].shape[0]
        for j, m in enumerate(mats):
            if m.shape != (n, n):
                raise InputError(f"stiffness_parts[{j}]: shape {m.shape} differs from ({n}, {n})")
        base_m = sum(mats[1:], mats[0]) if base is None else _as_csc(base, "base_stiffness")
        if base_m.shape != (n, n):
            raise InputError(f"base_stiffness: shape {base_m.shape} differs from ({n}, {n})")
        pattern = abs(base_m)
        for m in mats:
            pattern = pattern + abs(m)
        pattern = sp.csc_matrix(pattern)
        pattern.sum_duplicates()
        pattern.sort_indices()
        pattern.eliminate_zeros()
        self.n = n
        self.indices = pattern.indices.copy()
        self.indptr = pattern.indptr.copy()
        self.d0 = self._on_pattern(base_m, pattern)
        self.D = np.column_stack([self._on_pattern(m, pattern) for m in mats])

    @staticmethod
    def _on_pattern(m: sp.csc_matrix, pattern: sp.csc_matrix) -> np.ndarray:
        """Values of m at the entries of ``pattern`` (zeros where m has none)."""
        m = sp.csc_matrix(m)
        m.sum_duplicates()
        m.eliminate_zeros()
        n = pattern.shape[0]
        cols_p = np.repeat(np.arange(n), np.diff(pattern.indptr))
        keys_p = cols_p.astype(np.int64) * n + pattern.indices
        cols_m = np.repeat(np.arange(n), np.diff(m.indptr))
        keys_m = cols_m.astype(np.int64) * n + m.indices
        pos = np.searchsorted(keys_p, keys_m)
        values = np.zeros(pattern.nnz)
        values[pos] = m.data
        return values

    @property
    def n_parts(self) -> int:
        return int(self.D.shape[1])

    def part(self, j: int) -> sp.csc_matrix:
        """dK/dalpha_j = K_j as a sparse matrix (its own nonzeros only)."""
        cache = self.__dict__.setdefault("_parts", {})
        if j not in cache:
            m = sp.csc_matrix((self.D[:, j].copy(), self.indices.copy(), self.indptr.copy()), shape=(self.n, self.n))
            m.eliminate_zeros()
            cache[j] = m
        return cache[j]

    def __call__(self, alpha: np.ndarray) -> sp.csc_matrix:
        """K for one parameter vector alpha (J,)."""
        data = self.d0 + self.D @ np.asarray(alpha, dtype=float)
        return sp.csc_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))


def solve_shift_invert(K, M, n_modes: int, sigma: float = 0.0, tol: float = 0.0):
    """Lowest ``n_modes`` eigenpairs of K phi = lambda M phi via shift-invert Lanczos.

    Returns (lambda (n_modes,) ascending, phi (n, n_modes), M-normalized). Raises
    ModelEvaluationError for a singular K - sigma M, no convergence or lambda <= 0.
    """
    from scipy.sparse.linalg import ArpackNoConvergence, eigsh

    n = K.shape[0]
    if n_modes >= n - 1:
        raise ModelEvaluationError("too_few_modes", f"n_modes={n_modes} needs more than {n} DOFs")
    v0 = np.ones(n)  # fixed start vector: identical results on every call and process
    try:
        lam, phi = eigsh(sp.csc_matrix(K), k=n_modes, M=sp.csc_matrix(M), sigma=sigma, which="LM", v0=v0, tol=tol)
    except ArpackNoConvergence as exc:
        raise ModelEvaluationError("not_converged", f"ARPACK: {exc}") from exc
    except RuntimeError as exc:  # splu of a singular K - sigma M
        raise ModelEvaluationError("singular_matrix", f"K - sigma M: {exc}") from exc
    order = np.argsort(lam)
    lam, phi = lam[order], phi[:, order]
    return _check_positive(lam), phi


def solve_condensation(K, M, n_modes: int):
    """Lowest ``n_modes`` eigenpairs by exact static condensation of massless DOFs (dense).

    Massless DOFs s (zero row and column of M) carry no inertia, so K_ss phi_s + K_sm phi_m = 0
    exactly: phi_s = -K_ss^-1 K_sm phi_m and (K_mm - K_ms K_ss^-1 K_sm) phi_m = lambda M_mm phi_m.
    """
    Kd = K.toarray() if sp.issparse(K) else np.asarray(K, float)
    Md = M.toarray() if sp.issparse(M) else np.asarray(M, float)
    n = Kd.shape[0]
    massive = np.flatnonzero(np.any(Md != 0, axis=1) | np.any(Md != 0, axis=0))
    massless = np.setdiff1d(np.arange(n), massive)
    if n_modes > massive.size:
        raise ModelEvaluationError("too_few_modes", f"n_modes={n_modes} > {massive.size} DOFs with mass")
    try:
        if massless.size:
            Kss = Kd[np.ix_(massless, massless)]
            Ksm = Kd[np.ix_(massless, massive)]
            T = la.cho_solve(la.cho_factor(Kss), Ksm)
            Kc = Kd[np.ix_(massive, massive)] - Ksm.T @ T
        else:
            T = np.zeros((0, n))
            Kc = Kd
        Kc = 0.5 * (Kc + Kc.T)
        lam, phi_m = la.eigh(Kc, Md[np.ix_(massive, massive)], subset_by_index=[0, n_modes - 1])
    except la.LinAlgError as exc:
        raise ModelEvaluationError("singular_matrix", f"condensation/eigh: {exc}") from exc
    phi = np.empty((n, n_modes))
    phi[massive] = phi_m
    phi[massless] = -T @ phi_m
    return _check_positive(lam), phi


def _check_positive(lam: np.ndarray) -> np.ndarray:
    if not np.all(np.isfinite(lam)) or np.any(lam <= 0):
        raise ModelEvaluationError("indefinite_matrix", f"non-positive eigenvalue(s) {lam[lam <= 0].tolist()}")
    return lam


class MatrixModel:
    """A structural model K(alpha) = K_0 + sum_j alpha_j K_j, M (StructuralModel protocol).

    stiffness_parts: J matrices K_j (dense or sparse), one per parameter of ``parameters``
    in the same order; mass: M; measured_dofs: {label: 0-based DOF index} of the DOFs at
    which shapes are returned; base_stiffness: K_0 (default sum_j K_j); n_modes: modes
    computed; solver: "auto" | "shift_invert" | "condensation"; sigma: shift in rad^2/s^2.
    """

    def __init__(
        self,
        stiffness_parts: Sequence,
        mass,
        parameters: ParameterSet,
        measured_dofs: Mapping[str, int],
        *,
        base_stiffness=None,
        n_modes: int = 6,
        solver: str = "auto",
        sigma: float = 0.0,
        name: str = "matrix_model",
    ):
        if solver not in SOLVERS:
            raise InputError(f"solver must be one of {', '.join(map(repr, SOLVERS))}, got {solver!r}")
        if len(stiffness_parts) != len(parameters):
            raise InputError(
                f"stiffness_parts: {len(stiffness_parts)} matrices for {len(parameters)} parameters {parameters.names}"
            )
        self.stiffness = LinearStiffness(stiffness_parts, base_stiffness)
        self.mass = _as_csc(mass, "mass")
        n = self.stiffness.n
        if self.mass.shape != (n, n):
            raise InputError(f"mass: shape {self.mass.shape} differs from stiffness ({n}, {n})")
        if int(n_modes) < 1:
            raise InputError(f"n_modes must be >= 1, got {n_modes!r}")
        labels, index = list(measured_dofs), np.asarray(list(measured_dofs.values()), dtype=int)
        bad = index[(index < 0) | (index >= n)]
        if bad.size:
            raise InputError(f"measured_dofs: index {int(bad[0])} outside 0..{n - 1}")
        self._parameters = parameters
        self._dofs = tuple(str(lab) for lab in labels)
        self.dof_index = index
        self.n_modes = int(n_modes)
        self.sigma = float(sigma)
        self.solver = solver if solver != "auto" else ("condensation" if n <= DENSE_LIMIT else "shift_invert")
        self.name = name

    @property
    def parameters(self) -> ParameterSet:
        return self._parameters

    @property
    def dofs(self) -> tuple[str, ...]:
        return self._dofs

    @property
    def n_dof(self) -> int:
        return self.stiffness.n

    def stiffness_matrix(self, theta: Mapping[str, float]) -> sp.csc_matrix:
        values = full_theta(self._parameters, theta)
        return self.stiffness(np.array([values[n] for n in self._parameters.names]))

    def eigen(self, theta: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray]:
        """Eigenvalues lambda = omega^2 (rad^2/s^2) and full shapes (n_dof, n_modes)."""
        K = self.stiffness_matrix(theta)
        if self.solver == "condensation":
            return solve_condensation(K, self.mass, self.n_modes)
        if self.solver == "shift_invert_ldl" and self.sigma == 0.0:
            ldl = self._reused_ldl()
            if ldl is not None:
                from framework.models.repeated_eigen import NotApplicable, lowest_modes

                try:
                    return lowest_modes(K, self.mass, self.n_modes, ldl)
                except NotApplicable as exc:
                    log.debug("%s: reused LDL' path not applicable (%s); shift-invert from scratch", self.name, exc)
        return solve_shift_invert(K, self.mass, self.n_modes, self.sigma)

    def _reused_ldl(self):
        """The model's reused LDL' factorization (built once per process), None without qdldl."""
        if "_ldl" not in self.__dict__:
            from framework.models import repeated_eigen

            if repeated_eigen.available():
                self._ldl = repeated_eigen.ReusedLDL(self.stiffness(np.zeros(self.stiffness.n_parts)))
            else:
                log.warning("%s: solver 'shift_invert_ldl' needs the optional package qdldl (extra 'fast'); "
                            "using 'shift_invert'", self.name)
                self._ldl = None
        return self._ldl

    def __getstate__(self):
        state = dict(self.__dict__)
        state.pop("_ldl", None)  # rebuilt in the receiving process
        return state

    def modal(self, theta: Mapping[str, float]) -> ModalResult:
        """Modes at ``theta``; meta["eigenvectors"] keeps the full mass-normalized shapes (n_dof, n_modes)
        for :meth:`modal_derivatives`."""
        lam, phi = self.eigen(theta)
        return ModalResult(
            np.sqrt(lam) / (2.0 * math.pi),
            phi[self.dof_index],
            self._dofs,
            mode_info={"eigenvalue": lam},
            meta={"eigenvectors": phi},
        )

    # ---- derivatives ------------------------------------------------------------------
    def derivative_cost(self, n_modes: int, n_params: int) -> int:
        """Eigen-solve equivalents of :meth:`modal_derivatives` for n_modes modes: one factorization each."""
        return int(n_modes)

    def modal_derivatives(
        self,
        theta: Mapping[str, float],
        result: ModalResult | None = None,
        *,
        parameters: Sequence[str] | None = None,
        modes: Sequence[int] | None = None,
        close_rtol: float = CLOSE_EIGENVALUE_RTOL,
    ) -> ModalDerivatives:
        """Exact derivatives of the modes ``modes`` (default all) with respect to ``parameters``
        (names, default all): dK/dalpha_j = K_j (K is linear in alpha), dM = 0, Nelson's method
        (:mod:`framework.core.modal_derivatives`). ``result``: this model's ModalResult at theta (saves
        the eigen solution); raises CloseEigenvalues for a repeated or close eigenvalue."""
        names = list(self._parameters.names if parameters is None else parameters)
        cols = [self._parameters.names.index(n) for n in names]
        extra = 0
        if result is None or "eigenvectors" not in result.meta:
            result, extra = self.modal(theta), 1
        lam = np.asarray(result.mode_info["eigenvalue"], float)
        modes = np.arange(lam.size) if modes is None else np.asarray(modes, dtype=int)
        check_separated(lam, modes, close_rtol)
        phi = normalize_mass(self.mass, np.asarray(result.meta["eigenvectors"], float)[:, modes])
        dK_phi = np.stack([np.asarray(self.stiffness.part(j) @ phi) for j in cols], axis=2)
        dlam, dphi, n_fact = eigen_derivatives(self.stiffness_matrix(theta), self.mass, lam[modes], phi, dK_phi)
        return ModalDerivatives(modes, tuple(names), dlam, dphi[self.dof_index], n_fact + extra)

    def modal_batch(self, thetas: Sequence[Mapping[str, float]]) -> list:
        """Evaluate many points with BLAS limited to one thread (many small solves)."""
        from threadpoolctl import threadpool_limits

        with threadpool_limits(limits=1):
            return [safe_modal(self, t) for t in thetas]


# --------------------------------------------------------------------------------------
def load_matrices(path: str | Path, names: Sequence[str]) -> dict[str, sp.csc_matrix | np.ndarray]:
    """Read named matrices from a MATLAB .mat or a NumPy .npz file.

    Matrices (2-D, square) come back as scipy CSC; other arrays as NumPy arrays.
    """
    path = Path(path)
    if not path.exists():
        raise InputError(f"matrix file not found: {path}")
    suffix = path.suffix.lower()
    if suffix == ".mat":
        from scipy.io import loadmat

        data = loadmat(path)
    elif suffix == ".npz":
        with np.load(path, allow_pickle=False) as npz:
            data = {k: npz[k] for k in npz.files}
    else:
        raise InputError(f"{path}: unsupported matrix file type {suffix!r} (use .mat or .npz)")
    missing = [n for n in names if n not in data]
    if missing:
        known = sorted(k for k in data if not k.startswith("__"))
        raise InputError(f"{path}: missing matrix/matrices {missing}; file has {known}")
    out: dict = {}
    for n in names:
        value = data[n]
        if sp.issparse(value) or (np.ndim(value) == 2 and value.shape[0] == value.shape[1] and value.shape[0] > 1):
            out[n] = _as_csc(value, f"{path}:{n}")
        else:
            out[n] = np.asarray(value)
    return out


def from_file(
    path: str,
    stiffness: Sequence[str],
    mass: str,
    measured_dofs: Sequence[int] | str,
    *,
    bounds: Sequence[float] | Sequence[Sequence[float]] = (-0.5, 0.5),
    base_stiffness: str | None = None,
    parameter_names: Sequence[str] | None = None,
    one_based: bool = True,
    n_modes: int = 6,
    solver: str = "auto",
    sigma: float = 0.0,
    name: str | None = None,
) -> MatrixModel:
    """A MatrixModel from a .mat/.npz file, usable from a config as
    ``structure: {name: "framework.models.matrix:from_file", options: {path: ..., ...}}``.

    stiffness: names of the K_j; mass: name of M; measured_dofs: DOF numbers (1-based unless
    ``one_based`` is false) or the name of an array of them in the file; bounds: one
    (lower, upper) pair for every alpha_j or one pair per parameter; parameter_names:
    default ``alpha_1`` .. ``alpha_J``. DOF labels are ``dof<number>`` as given.
    """
    from framework.core.parameters import Parameter

    wanted = [*stiffness, mass] + ([base_stiffness] if base_stiffness else [])
    wanted += [measured_dofs] if isinstance(measured_dofs, str) else []
    data = load_matrices(path, wanted)
    numbers = np.asarray(data[measured_dofs] if isinstance(measured_dofs, str) else measured_dofs).ravel()
    numbers = numbers.astype(int)
    names = list(parameter_names) if parameter_names else [f"alpha_{j + 1}" for j in range(len(stiffness))]
    if len(names) != len(stiffness):
        raise InputError(f"parameter_names: {len(names)} names for {len(stiffness)} stiffness matrices")
    pairs = np.asarray(bounds, dtype=float)
    if pairs.shape == (2,):
        pairs = np.tile(pairs, (len(names), 1))
    if pairs.shape != (len(names), 2):
        raise InputError(f"bounds: expected one (lower, upper) pair or {len(names)} pairs, got {bounds!r}")
    params = ParameterSet(
        Parameter(n, 0.0, float(lo), float(hi), "-", f"relative change of {k}")
        for n, (lo, hi), k in zip(names, pairs, stiffness)
    )
    offset = 1 if one_based else 0
    return MatrixModel(
        [data[k] for k in stiffness],
        data[mass],
        params,
        {f"dof{d}": int(d) - offset for d in numbers},
        base_stiffness=data[base_stiffness] if base_stiffness else None,
        n_modes=n_modes,
        solver=solver,
        sigma=sigma,
        name=name or Path(path).stem,
    )
