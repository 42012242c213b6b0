"""External benchmark data (SMU package): four-storey shear frame and steel footbridge.

The data files are *read* from ``<project>/../shared/benchmarks/smu/`` (or the folder in
the environment variable ``GOMU_SMU_DIR``); they are never copied into the project.
See that folder's README.md for their content. Structures and measured data, registered as
``four_story`` and ``footbridge`` (:mod:`.descriptor`; ``structure: {name: four_story}``,
``measured: {builtin: four_story, case: ...}`` in a config):

- :func:`make_four_story` / :func:`four_story_measured` (cases "base": floors
  1-3 and modes 1-2 as in the reference; "all_floors": floors 1-4, modes 1-2; "all":
  floors 1-4, modes 1-4). Units lbf, in, s: floor mass 12.060 lb / 386.088 in/s^2,
  nominal storey stiffness 10 lbf/in, k_i = 10 (1 + alpha_i), alpha_i in [-1, 1].
- :func:`make_footbridge` / :func:`footbridge_measured`: 946-DOF model
  K = sum_j (1 + alpha_j) K_j over 17 substructures, singular M0, 58 measured DOFs
  (labels ``dof<n>``, n the 1-based DOF number of the source), 5 measured modes with
  eigenvalue and shape standard deviations.

Both are :class:`~framework.models.matrix.MatrixModel` s, so they provide exact modal
derivatives (``modal_derivatives``: K linear in alpha, Nelson's method; the footbridge's
singular M0 and 946 DOFs through sparse factorizations).
"""

from __future__ import annotations

import functools
import math
import os
from pathlib import Path

import numpy as np

from framework.core.errors import InputError
from framework.core.parameters import Parameter, ParameterSet
from framework.measured.modes import MeasuredModes
from framework.models.matrix import MatrixModel, load_matrices
from framework.models.shear_building import ShearBuilding, make_shear_building

ENV_VAR = "GOMU_SMU_DIR"
FOUR_STORY_FILE = "four_story_modes.mat"
FOOTBRIDGE_MODEL_FILE = "steel_footbridge_model.mat"
FOOTBRIDGE_MODES_FILE = "steel_footbridge_modes.mat"

#: Four-storey frame (lbf, in, s).
GRAVITY_IN_S2 = 386.088
FLOOR_WEIGHT_LB = 12.060
FLOOR_MASS = FLOOR_WEIGHT_LB / GRAVITY_IN_S2  # lbf s^2 / in
STOREY_STIFFNESS_LBF_PER_IN = 10.0

#: Footbridge substructures, in the order of the parameters alpha_1..alpha_17.
FOOTBRIDGE_PARTS = ["K_Frame", "K_Truss"] + [f"K_Conc{i}" for i in range(1, 12)] + ["K_y1", "K_z1", "K_y2", "K_z2"]
FOOTBRIDGE_DESCRIPTIONS = (
    ["steel frame members", "truss members"]
    + [f"concrete deck slab {i}" for i in range(1, 12)]
    + ["support spring y1", "support spring z1", "support spring y2", "support spring z2"]
)


def _bounds(j: int) -> tuple[float, float]:
    """Reference bounds: alpha_1..2 in [-0.1, 0.1], 3..13 in [-0.2, 0.4], 14..17 in [-1, 10]."""
    if j < 2:
        return -0.1, 0.1
    if j < 13:
        return -0.2, 0.4
    return -1.0, 10.0


FOOTBRIDGE_PARAMETERS = ParameterSet(
    Parameter(f"alpha_{j + 1}", 0.0, *_bounds(j), "-", f"relative stiffness change: {desc}")
    for j, desc in enumerate(FOOTBRIDGE_DESCRIPTIONS)
)


def smu_dir() -> Path:
    """Folder of the SMU data: $GOMU_SMU_DIR or <project>/../shared/benchmarks/smu."""
    env = os.environ.get(ENV_VAR)
    if env:
        return Path(env)
    return (Path(__file__).resolve().parents[4] / "shared" / "benchmarks" / "smu").resolve()


def available() -> bool:
    """True when all three SMU data files are present."""
    d = smu_dir()
    return all((d / f).exists() for f in (FOUR_STORY_FILE, FOOTBRIDGE_MODEL_FILE, FOOTBRIDGE_MODES_FILE))


def _path(name: str) -> Path:
    path = smu_dir() / name
    if not path.exists():
        raise InputError(f"SMU benchmark file not found: {path} (set {ENV_VAR} to the folder holding {name})")
    return path


# ---- four-storey shear frame -------------------------------------------------------------
FOUR_STORY_CASES = {
    "base": ((1, 2, 3), (1, 2)),
    "all_floors": ((1, 2, 3, 4), (1, 2)),
    "all": ((1, 2, 3, 4), (1, 2, 3, 4)),
}


def _case(case: str, cases: dict, what: str):
    if case not in cases:
        raise InputError(f"{what}: unknown case {case!r}; known: {sorted(cases)}")
    return cases[case]


def make_four_story(measured_floors=(1, 2, 3, 4), n_modes: int = 4) -> ShearBuilding:
    """Four-storey shear frame: 4 floors of 12.060 lb, storeys 10 (1 + alpha_i) lbf/in."""
    return make_shear_building(
        [FLOOR_MASS] * 4,
        [STOREY_STIFFNESS_LBF_PER_IN] * 4,
        measured_floors=measured_floors,
        n_modes=n_modes,
        name="four_story",
    )


def four_story_measured(case: str = "base") -> MeasuredModes:
    """Identified frequencies and shapes of the four-storey frame (floors x modes of ``case``)."""
    from scipy.io import loadmat

    floors, modes = _case(case, FOUR_STORY_CASES, "four_story_measured")
    path = _path(FOUR_STORY_FILE)
    data = loadmat(path)
    f = np.asarray(data["test_frequency"], float).ravel()
    phi = np.asarray(data["test_mode"], float)
    rows, cols = [i - 1 for i in floors], [j - 1 for j in modes]
    return MeasuredModes(
        frequencies_hz=f[cols],
        dofs=tuple(f"floor{i}" for i in floors),
        shapes=phi[np.ix_(rows, cols)],
        labels=tuple(f"mode {j}" for j in modes),
        name=f"four_story_{case}",
        source=str(path),
    )


# ---- steel footbridge --------------------------------------------------------------------
@functools.lru_cache(maxsize=2)
def _footbridge_matrices(path: str) -> tuple:
    data = load_matrices(path, [*FOOTBRIDGE_PARTS, "M0", "measDOFs"])
    meas = np.asarray(data["measDOFs"]).ravel().astype(int)
    return tuple(data[n] for n in FOOTBRIDGE_PARTS), data["M0"], meas


def make_footbridge(n_modes: int = 5, solver: str = "shift_invert", sigma: float = 0.0) -> MatrixModel:
    """946-DOF footbridge: K = sum_j (1 + alpha_j) K_j, M0; shapes at the 58 measured DOFs."""
    parts, mass, meas = _footbridge_matrices(str(_path(FOOTBRIDGE_MODEL_FILE)))
    return MatrixModel(
        parts,
        mass,
        FOOTBRIDGE_PARAMETERS,
        {f"dof{d}": d - 1 for d in meas},
        n_modes=n_modes,
        solver=solver,
        sigma=sigma,
        name="steel_footbridge",
    )


def footbridge_measured(case: str = "base") -> MeasuredModes:
    """Five measured modes: f = sqrt(lambda)/2 pi, shapes, std of f (from std of lambda) and shapes.

    std_f = f std_lambda / (2 lambda) (first order, so that std_lambda = 2 lambda std_f / f
    is recovered exactly by the reference formulation).
    """
    from scipy.io import loadmat

    if case != "base":
        raise InputError(f"footbridge_measured: unknown case {case!r}; known: ['base']")
    _, _, meas = _footbridge_matrices(str(_path(FOOTBRIDGE_MODEL_FILE)))
    path = _path(FOOTBRIDGE_MODES_FILE)
    data = loadmat(path)
    lam = np.asarray(data["lambdaExp"], float).ravel()
    std_lam = np.asarray(data["std_lambdaExp"], float).ravel()
    f = np.sqrt(lam) / (2.0 * math.pi)
    return MeasuredModes(
        frequencies_hz=f,
        dofs=tuple(f"dof{d}" for d in meas),
        shapes=np.asarray(data["psiExp_m"], float),
        labels=tuple(f"mode {j + 1}" for j in range(lam.size)),
        frequency_std_hz=f * std_lam / (2.0 * lam),
        shape_std=np.asarray(data["std_psiExp"], float),
        name="steel_footbridge",
        source=str(path),
        meta={
            "lambda_rad2_per_s2": lam.tolist(),
            "std_lambda_rad2_per_s2": std_lam.tolist(),
            "n_tests": np.asarray(data["numTest"]).ravel().tolist(),
        },
    )
