"""Laboratory frame (bookshelf type): 3-DOF analytical model and the measured data (SPEC 5).

Rigid slab with DOFs [u_x, u_y, u_theta] at the slab's geometric centre; one equivalent
column with translational stiffnesses kxx, kyy, coupling kxy, torsional stiffness krr and
elastic-centre eccentricities ex, ey:

    K = [[kxx,              kxy,              -kxx ey + kxy ex],
         [kxy,              kyy,              -kxy ey + kyy ex],
         [-kxx ey + kxy ex, -kxy ey + kyy ex,  kxx ey^2 - 2 kxy ex ey + kyy ex^2 + krr]]
    M = [[mt, 0, -ycm mt], [0, mt, mt xcm], [-ycm mt, mt xcm, J]]

K phi = omega^2 M phi, f = omega / 2 pi. Shapes are reported at the measured DOFs
"y", "x" and "torsion".

Torsion congruence (``congruence``). The source relates measured and model coordinates by
T = diag(1, 1, b/2) (b = 0.65 m, slab width) without saying which side it multiplies; the
published torsion column is labelled "x b/2". With a = [u_y, u_x, u_theta] of the model
and e the published column [y, x, torsion], the readings are (MAC is not invariant to
scaling one row, so they differ):

    model     MAC(T a, e)       model rotation times b/2 against the column as published
    measured  MAC(a, T^-1 e)    column divided by b/2 (back to radians) against the rotation
    unscaled  MAC(a, e)         rotation against the column, no scaling
    inverse   MAC(T^-1 a, e)    model rotation divided by b/2 against the column

The model scales its torsion row and :func:`measured` its torsion column by the factors in
:data:`CONGRUENCES`; both default to :data:`DEFAULT_CONGRUENCE` = "measured", the reading
that reproduces the source's initial-model MACs and minimum most closely
(studies/lab_frame_congruence.yaml, results/lab_frame_congruence/congruence.csv:
initial MACs 0.9999 / 0.9948 / 0.9984 against the source's 0.989 / 0.974 / 0.999,
minimum 1.65e-6 against "about 1.3e-6"; "model" gives 1.6e-5). Data in sensor units
(the simulated identification, which measures theta b/2) go with "model".

Added mass (validation): a rigid block of mass m at the slab centre (the origin) gives
mt' = mt + m, unchanged static moments mt xcm, mt ycm, and J' = J + J_block, the block's
own polar moment about its vertical axis. Our assumption (the source gives only the
masses): a compact steel cylinder (7850 kg/m^3) with height equal to its diameter,
d = (4 m / (pi rho))^(1/3), J_block = m d^2 / 8 (0.654 kg: d = 47 mm, 1.8e-4 kg m^2;
1.379 kg: d = 61 mm, 6.3e-4 kg m^2; 0.01-0.05 % of J). ``added_block="point"`` drops J_block.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from framework.core.errors import InputError, ModelEvaluationError
from framework.core.parameters import Parameter, ParameterSet
from framework.measured.modes import MeasuredModes
from framework.models.arrays import ModalArrays, theta_matrix
from framework.models.base import ModalResult, full_theta
from framework.models.geometry import ModelShapes
from framework.structures.lab_frame.geometry import SLAB_WIDTH_M, slab_on_columns

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

#: Torsion congruence readings: (factor on the model's rotation, factor on the published
#: torsion column); see the module docstring.
CONGRUENCES = {
    "model": (SLAB_WIDTH_M / 2.0, 1.0),
    "measured": (1.0, 2.0 / SLAB_WIDTH_M),
    "unscaled": (1.0, 1.0),
    "inverse": (2.0 / SLAB_WIDTH_M, 1.0),
}
DEFAULT_CONGRUENCE = "measured"

#: Added block (our assumption): compact steel cylinder, height = diameter.
BLOCK_DENSITY_KG_M3 = 7850.0
ADDED_BLOCKS = ("cylinder", "point")


def congruence_factors(congruence: str) -> tuple[float, float]:
    """(model rotation factor, published torsion column factor) of a congruence reading."""
    if congruence not in CONGRUENCES:
        raise InputError(f"lab frame: unknown congruence {congruence!r}; known: {list(CONGRUENCES)}")
    return CONGRUENCES[congruence]


def block_dimensions(mass_kg: float, density_kg_m3: float = BLOCK_DENSITY_KG_M3) -> dict[str, float]:
    """Cylinder with h = d of mass m: d = (4 m / (pi rho))^(1/3); its own moments of inertia
    J_z = m d^2 / 8 (about the vertical axis) and J_x = J_y = m (3 r^2 + h^2) / 12."""
    if mass_kg < 0:
        raise InputError(f"lab frame: added mass must be >= 0 kg, got {mass_kg!r}")
    d = (4.0 * mass_kg / (math.pi * density_kg_m3)) ** (1.0 / 3.0)
    r = d / 2.0
    return {
        "diameter_m": d,
        "height_m": d,
        "polar_inertia_kg_m2": mass_kg * d**2 / 8.0,
        "rocking_inertia_kg_m2": mass_kg * (3.0 * r**2 + d**2) / 12.0,
    }


def block_polar_inertia(mass_kg: float, added_block: str = "cylinder") -> float:
    """J_block of the added mass about its vertical axis (0 for a point mass)."""
    if added_block not in ADDED_BLOCKS:
        raise InputError(f"lab frame: unknown added_block {added_block!r}; known: {list(ADDED_BLOCKS)}")
    return 0.0 if added_block == "point" else block_dimensions(mass_kg)["polar_inertia_kg_m2"]


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


def mass_matrix(mt=MASS_KG, J=POLAR_INERTIA_KG_M2, xcm=XCM_M, ycm=YCM_M, added_mass_kg=0.0,
                added_polar_kg_m2=0.0) -> np.ndarray:
    """M of the 3-DOF model, with an optional block of mass m and own polar moment J_block at
    the slab centre: mt' = mt + m, J' = J + J_block."""
    m = mt + added_mass_kg
    sx, sy = mt * xcm, mt * ycm  # static moments, unchanged by a mass at the origin
    return np.array([[m, 0.0, -sy], [0.0, m, sx], [-sy, sx, J + added_polar_kg_m2]])


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


def _to_measured_dofs(phi: np.ndarray, torsion_factor: float) -> np.ndarray:
    """Rows [u_x, u_y, u_theta] -> [y, x, c theta] (c from the congruence reading)."""
    return np.stack([phi[..., 1, :], phi[..., 0, :], phi[..., 2, :] * torsion_factor], axis=-2)


@dataclass(frozen=True)
class ThreeDofFrame:
    """The 3-DOF analytical model; ``modal_batch`` solves a whole population at once."""

    added_mass_kg: float = 0.0
    added_polar_kg_m2: float = 0.0
    congruence: str = DEFAULT_CONGRUENCE
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
        return mass_matrix(self.mt, self.J, self.xcm, self.ycm, self.added_mass_kg, self.added_polar_kg_m2)

    @property
    def torsion_factor(self) -> float:
        return congruence_factors(self.congruence)[0]

    def stiffness(self, theta: Mapping[str, float]) -> np.ndarray:
        v = full_theta(PARAMETERS, theta)
        return stiffness_matrix(v["kxx"], v["kyy"], v["kxy"], v["krr"], v["ex"], v["ey"])

    def modal(self, theta: Mapping[str, float]) -> ModalResult:
        f, phi = modes_from_matrices(self.stiffness(theta), self.mass())
        return ModalResult(f, _to_measured_dofs(phi, self.torsion_factor), DOFS)

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
        phi = _to_measured_dofs(Li.T @ psi, self.torsion_factor)
        bad = np.flatnonzero(np.any(w2 <= 0, axis=1))
        errors = {int(i): ModelEvaluationError("indefinite_matrix", f"eigenvalues {w2[i].tolist()}") for i in bad}
        return ModalArrays(np.sqrt(np.maximum(w2, 0.0)) / (2 * math.pi), phi, DOFS, errors)

    def geometry(self, theta: Mapping[str, float], shapes: ModelShapes) -> ModelShapes:
        """How its modes are drawn: the rigid slab on four columns, sensors at the slab corners
        (:mod:`framework.structures.lab_frame.geometry`)."""
        return slab_on_columns(shapes)


def make_model(added_mass_kg: float = 0.0, case: str | None = None, congruence: str = DEFAULT_CONGRUENCE,
               added_block: str = "cylinder") -> ThreeDofFrame:
    """The 3-DOF model; ``case`` (a key of CASES) sets the added mass, ``added_block`` its
    shape ("cylinder": steel, h = d, with its own polar moment; "point": none),
    ``congruence`` the torsion reading (a key of CONGRUENCES)."""
    if case is not None:
        if case not in CASES:
            raise InputError(f"lab frame: unknown case {case!r}; known: {list(CASES)}")
        added_mass_kg = CASES[case]
    congruence_factors(congruence)
    return ThreeDofFrame(added_mass_kg=float(added_mass_kg),
                         added_polar_kg_m2=block_polar_inertia(float(added_mass_kg), added_block),
                         congruence=congruence)


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


def measured(case: str = "base", congruence: str = DEFAULT_CONGRUENCE) -> MeasuredModes:
    """Measured modes of the lab frame for a case: base or an added-mass case; the torsion
    row is the published column times the congruence reading's factor (1/(b/2) for
    "measured": radians).

    Shapes were measured in the base configuration only; the added-mass cases reuse them
    for pairing (the masses sit at the centre and barely change the shapes) and are used
    for validation, never for updating.
    """
    if case not in _FREQUENCIES:
        raise InputError(f"lab frame: unknown measured case {case!r}; known: {list(_FREQUENCIES)}")
    shapes = _BASE_SHAPES.copy()
    shapes[2] *= congruence_factors(congruence)[1]
    return MeasuredModes(
        frequencies_hz=np.array(_FREQUENCIES[case]),
        dofs=DOFS,
        shapes=shapes,
        damping_ratio=DAMPING_RATIO.copy() if case == "base" else None,
        labels=("1st y", "1st x", "1st torsion"),
        name=f"lab_frame_{case}",
        source=f"SPEC 5 lab frame ({case})",
    )
