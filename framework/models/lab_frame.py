"""Laboratory frame (bookshelf type): 3-DOF analytical model and the measured data (SPEC 5).

Rigid slab with DOFs [u_x, u_y, u_theta] at the slab's geometric centre; one equivalent
column with translational stiffnesses kxx, kyy, coupling kxy, torsional stiffness krr and
elastic-centre eccentricities ex, ey:

    K = [[kxx,              kxy,              -kxx ey + kxy ex],
         [kxy,              kyy,              -kxy ey + kyy ex],
         [-kxx ey + kxy ex, -kxy ey + kyy ex,  kxx ey^2 - 2 kxy ex ey + kyy ex^2 + krr]]
    M = [[mt, 0, -ycm mt], [0, mt, mt xcm], [-ycm mt, mt xcm, J]]

K phi = omega^2 M phi, f = omega / 2 pi. Shapes are reported at the measured DOFs
"y", "x" and "torsion", the last being the rotation times b/2 (b = 0.65 m, slab width) so
that it is in metres like the translations.

Added mass (validation): a point mass m at the slab centre (the origin) gives
mt' = mt + m and unchanged static moments mt xcm, mt ycm and polar moment J about the
origin (the mass's own rotational inertia is neglected: a 0.65-1.4 kg block of ~0.1 m
size adds < 0.002 kg m^2, 0.1 % of J).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from framework.errors import InputError, ModelEvaluationError
from framework.measurements import MeasuredModes
from framework.models.arrays import ModalArrays, theta_matrix
from framework.models.base import ModalResult, full_theta
from framework.parameters import Parameter, ParameterSet

SLAB_WIDTH_M = 0.65
DOFS = ("y", "x", "torsion")

#: Fixed mass properties of the frame (SPEC 5).
MASS_KG = 17.5
POLAR_INERTIA_KG_M2 = 1.2645
XCM_M = -0.0103
YCM_M = 0.0062

PARAMETERS = ParameterSet(
    [
        Parameter("kyy", 8904.0, 7000.0, 10600.0, "N/m", "lateral stiffness in y"),
        Parameter("kxx", 20294.0, 16000.0, 24500.0, "N/m", "lateral stiffness in x"),
        Parameter("kxy", 0.0, -500.0, 500.0, "N/m", "x-y coupling stiffness"),
        Parameter("krr", 3067.8, 2500.0, 3500.0, "N m", "torsional stiffness"),
        Parameter("ex", 0.0, -0.1, 0.1, "m", "x eccentricity of the elastic centre"),
        Parameter("ey", 0.0, -0.1, 0.1, "m", "y eccentricity of the elastic centre"),
    ]
)

#: Added-mass validation cases (mass at the slab centre, kg).
CASES = {"base": 0.0, "mass_0.654kg": 0.654, "mass_1.379kg": 1.379}


def stiffness_matrix(kxx, kyy, kxy, krr, ex, ey) -> np.ndarray:
    """K of the 3-DOF model; arguments may be arrays of equal shape (returns (..., 3, 3))."""
    kxx, kyy, kxy, krr, ex, ey = np.broadcast_arrays(
        *(np.asarray(v, float) for v in (kxx, kyy, kxy, krr, ex, ey))
    )
    k13 = -kxx * ey + kxy * ex
    k23 = -kxy * ey + kyy * ex
    k33 = kxx * ey**2 - 2.0 * kxy * ex * ey + kyy * ex**2 + krr
    return np.stack(
        [np.stack([kxx, kxy, k13], -1), np.stack([kxy, kyy, k23], -1), np.stack([k13, k23, k33], -1)], -2
    )


def mass_matrix(mt=MASS_KG, J=POLAR_INERTIA_KG_M2, xcm=XCM_M, ycm=YCM_M, added_mass_kg=0.0) -> np.ndarray:
    """M of the 3-DOF model, with an optional point mass at the slab centre."""
    m = mt + added_mass_kg
    sx, sy = mt * xcm, mt * ycm  # static moments, unchanged by a mass at the origin
    return np.array([[m, 0.0, -sy], [0.0, m, sx], [-sy, sx, J]])


def modes_from_matrices(K: np.ndarray, M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Solve K phi = omega^2 M phi for a stack of K (..., 3, 3) with one M.

    Uses the Cholesky factor M = L L^T: A = L^-1 K L^-T is symmetric, eigh(A) gives
    omega^2 and psi, phi = L^-T psi (mass-normalized). Returns f_hz (..., 3), phi (..., 3, 3).
    """
    L = np.linalg.cholesky(M)
    Li = np.linalg.inv(L)
    A = Li @ K @ Li.T
    A = 0.5 * (A + np.swapaxes(A, -1, -2))
    w2, psi = np.linalg.eigh(A)
    if np.any(w2 <= 0):
        raise ModelEvaluationError("indefinite_matrix", f"non-positive eigenvalue {w2.min():.4g}")
    phi = Li.T @ psi
    return np.sqrt(w2) / (2.0 * math.pi), phi


def _to_measured_dofs(phi: np.ndarray) -> np.ndarray:
    """Rows [u_x, u_y, u_theta] -> [y, x, theta b/2]."""
    return np.stack([phi[..., 1, :], phi[..., 0, :], phi[..., 2, :] * SLAB_WIDTH_M / 2.0], axis=-2)


@dataclass(frozen=True)
class ThreeDofFrame:
    """The 3-DOF analytical model; ``modal_batch`` solves a whole population at once."""

    added_mass_kg: float = 0.0
    mt: float = MASS_KG
    J: float = POLAR_INERTIA_KG_M2
    xcm: float = XCM_M
    ycm: float = YCM_M
    name: str = "lab_frame_3dof"

    @property
    def parameters(self) -> ParameterSet:
        return PARAMETERS

    @property
    def dofs(self) -> tuple[str, ...]:
        return DOFS

    def mass(self) -> np.ndarray:
        return mass_matrix(self.mt, self.J, self.xcm, self.ycm, self.added_mass_kg)

    def stiffness(self, theta: Mapping[str, float]) -> np.ndarray:
        v = full_theta(PARAMETERS, theta)
        return stiffness_matrix(v["kxx"], v["kyy"], v["kxy"], v["krr"], v["ex"], v["ey"])

    def modal(self, theta: Mapping[str, float]) -> ModalResult:
        f, phi = modes_from_matrices(self.stiffness(theta), self.mass())
        return ModalResult(f, _to_measured_dofs(phi), DOFS)

    def modal_batch(self, thetas: Sequence[Mapping[str, float]]) -> list:
        """Vectorized: one batched Cholesky-reduced eigh for all points (see ``modal_arrays``)."""
        if len(thetas) == 0:
            return []
        values = [full_theta(PARAMETERS, t) for t in thetas]
        theta = np.array([[v[n] for n in PARAMETERS.names] for v in values])
        return self.modal_arrays(theta, PARAMETERS.names).results()

    def modal_arrays(self, theta: np.ndarray, names: Sequence[str]) -> ModalArrays:
        """Modes of points theta (n, len(names)) as arrays (:mod:`framework.models.arrays`): K of
        every point stacked (n, 3, 3), A = L^-1 K L^-T with M = L L^T, one batched eigh."""
        cols = theta_matrix(PARAMETERS, theta, names)
        K = stiffness_matrix(cols["kxx"], cols["kyy"], cols["kxy"], cols["krr"], cols["ex"], cols["ey"])
        L = np.linalg.cholesky(self.mass())
        Li = np.linalg.inv(L)
        A = Li @ K @ Li.T
        w2, psi = np.linalg.eigh(0.5 * (A + np.swapaxes(A, -1, -2)))
        phi = _to_measured_dofs(Li.T @ psi)
        bad = np.flatnonzero(np.any(w2 <= 0, axis=1))
        errors = {int(i): ModelEvaluationError("indefinite_matrix", f"eigenvalues {w2[i].tolist()}") for i in bad}
        return ModalArrays(np.sqrt(np.maximum(w2, 0.0)) / (2 * math.pi), phi, DOFS, errors)

def make_model(added_mass_kg: float = 0.0, case: str | None = None) -> ThreeDofFrame:
    """The 3-DOF model; ``case`` (a key of CASES) sets the added mass."""
    if case is not None:
        if case not in CASES:
            raise InputError(f"lab frame: unknown case {case!r}; known: {list(CASES)}")
        added_mass_kg = CASES[case]
    return ThreeDofFrame(added_mass_kg=float(added_mass_kg))


# ---- measured data (SPEC 5: input-output subspace identification, mean of three tests) ----
_BASE_SHAPES = np.array(
    [  # columns = modes 1..3, rows = y, x, torsion (x b/2)
        [1.00, 0.07, -0.07],
        [0.004, 1.00, -0.02],
        [-0.01, -0.03, 1.00],
    ]
)
_FREQUENCIES = {
    "base": [3.58, 5.01, 7.28],
    "mass_0.654kg": [3.54, 4.90, 7.21],
    "mass_1.379kg": [3.48, 4.79, 7.10],
}
DAMPING_RATIO = np.array([0.0121, 0.0078, 0.0081])


def measured(case: str = "base") -> MeasuredModes:
    """Measured modes of the lab frame for a case: base or an added-mass case.

    Shapes were measured in the base configuration only; the added-mass cases reuse them
    for pairing (the masses sit at the centre and barely change the shapes) and are used
    for validation, never for updating.
    """
    if case not in _FREQUENCIES:
        raise InputError(f"lab frame: unknown measured case {case!r}; known: {list(_FREQUENCIES)}")
    return MeasuredModes(
        frequencies_hz=np.array(_FREQUENCIES[case]),
        dofs=DOFS,
        shapes=_BASE_SHAPES.copy(),
        damping_ratio=DAMPING_RATIO.copy() if case == "base" else None,
        labels=("1st y", "1st x", "1st torsion"),
        name=f"lab_frame_{case}",
        source=f"SPEC 5 lab frame ({case})",
    )
