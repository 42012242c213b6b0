"""Simply supported concrete beam for damage estimation (SPEC 7), in OpenSeesPy and plain numpy.

Geometry and material: L = 5 m, b = 0.25 m, h = 0.2 m, A = b h = 0.05 m^2,
I = b h^3 / 12 = 1.667e-4 m^4, E = 3.2e10 Pa, rho = 2500 kg/m^3; 2D Euler-Bernoulli
elements, pinned at x = 0 and x = L (vertical DOF fixed at both ends).

Modelling choices (documented because they decide the reference numbers):

- Mass: *lumped*, rho A l_e / 2 on the translational DOFs of each element end, no
  rotational inertia (OpenSees ``elasticBeamColumn`` default). It reproduces the SPEC
  reference frequencies to all given digits: 20 elements 12.98, 51.91, 116.80, 207.63,
  324.36 Hz; 10 elements 12.98, 51.91, 116.73, 207.14, 322.11 Hz. (A consistent mass
  gives 324.55 Hz and 325.74 Hz for mode 5, i.e. not the reference.)
- Axial DOFs are fixed at every node: in a straight beam bending and axial motion are
  uncoupled, and the first axial mode (about c / 4L = 179 Hz with a roller) would
  otherwise fall among the first five bending modes.
- Eigen solver: ``-fullGenLapack`` (the rotational DOFs are massless; ARPACK cannot
  build its Arnoldi basis for the 10-element mesh, which has only 9 mass DOFs; the full
  solver is exact and cheap for 30 DOFs).
- Measured DOFs: the vertical translations of the 9 interior nodes of the 10-element
  mesh, at x = 0.5, 1.0, ..., 4.5 m (labels ``uy_x0.50`` ...). The support nodes have
  zero vertical displacement in every mode and the multiplicative noise of SPEC 7 keeps
  them zero, so adding them ("10 DOFs") would not change any MAC value; a 10-element mesh
  has no 10th non-zero vertical DOF. The 20-element truth model exposes the same labels
  (its even nodes), so its modes serve as measurements of the 10-element model.
- Parameters: the I multiplier of each element, ``ratio_01`` ... (initial 1).

Damage states of the 20-element truth (1-based 20-element numbers; the 10-element
element e is made of 20-element elements 2e-1 and 2e):

- ``state1``: element 12 (second half of 10-element element 6) at 0.8 I;
- ``state2``: element 12 at 0.7 I and element 6 (second half of element 3) at 0.8 I.

SPEC 7 leaves open which half carries the damage but gives the truth's damaged frequencies
(:data:`SOURCE_DAMAGED_FREQUENCIES_HZ`); the second halves reproduce them within 0.03 %,
the first halves miss by up to 1.2 % (``studies/beam_truth.yaml``, ``results/beam_truth/``).

The truth ratio of a 10-element element is the mean of its halves (SPEC 7): 0.9 for
element 6 in state 1; 0.85 (element 6) and 0.9 (element 3) in state 2.

Two backends of the same model: :func:`make_opensees_model` (the framework's
bring-your-own-model path) and :class:`BeamNumpyModel` (same matrices in numpy,
vectorized over a batch of parameter points; agrees with OpenSees to ~1e-12).
"""

from __future__ import annotations

import functools
import logging
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from framework.core.errors import InputError, ModelEvaluationError
from framework.core.modal_derivatives import (
    CLOSE_EIGENVALUE_RTOL,
    ModalDerivatives,
    check_separated,
    eigen_derivatives,
    normalize_mass,
)
from framework.core.parameters import Parameter, ParameterSet
from framework.models.base import ModalResult, full_theta

log = logging.getLogger(__name__)

LENGTH_M = 5.0
WIDTH_M = 0.25
DEPTH_M = 0.2
AREA_M2 = WIDTH_M * DEPTH_M
INERTIA_M4 = WIDTH_M * DEPTH_M**3 / 12.0
YOUNG_PA = 3.2e10
DENSITY_KG_PER_M3 = 2500.0

N_ELEMENTS_APRIORI = 10
N_ELEMENTS_TRUTH = 20
#: default bounds of the stiffness ratios (damage lowers I; a little room above 1)
RATIO_LOWER = 0.5
RATIO_UPPER = 1.2

#: I multipliers of the 20-element truth per damage state: {1-based 20-element number: ratio}
DAMAGE_STATES: dict[str, dict[int, float]] = {
    "intact": {},
    "state1": {12: 0.8},
    "state2": {12: 0.7, 6: 0.8},
}

#: SPEC 7: the source's first five frequencies of the damaged 20-element beams (Hz)
SOURCE_DAMAGED_FREQUENCIES_HZ = {
    "state1": (12.83, 51.78, 115.99, 206.04, 323.64),
    "state2": (12.64, 51.07, 115.04, 204.71, 320.15),
}

#: SPEC 7 reference frequencies of the intact beams (Hz)
REFERENCE_FREQUENCIES_HZ = {
    20: (12.98, 51.91, 116.80, 207.63, 324.36),
    10: (12.98, 51.91, 116.73, 207.14, 322.11),
}


def ratio_names(n_elements: int) -> list[str]:
    """Parameter names ``ratio_01`` ... of the element I multipliers."""
    return [f"ratio_{i + 1:02d}" for i in range(n_elements)]


def beam_parameters(
    n_elements: int = N_ELEMENTS_APRIORI, lower: float = RATIO_LOWER, upper: float = RATIO_UPPER
) -> ParameterSet:
    """One I multiplier per element, initial 1, bounds [lower, upper]."""
    return ParameterSet(
        Parameter(name, 1.0, lower, upper, "-", f"I multiplier of element {i + 1}")
        for i, name in enumerate(ratio_names(n_elements))
    )


def sensor_positions_m(n_sensors: int = N_ELEMENTS_APRIORI - 1) -> np.ndarray:
    """x of the measured vertical DOFs: interior nodes of the 10-element mesh."""
    return LENGTH_M * np.arange(1, n_sensors + 1) / (n_sensors + 1)


def dof_labels() -> tuple[str, ...]:
    """Labels ``uy_x0.50`` ... of the measured vertical DOFs."""
    return tuple(f"uy_x{x:.2f}" for x in sensor_positions_m())


def _sensor_nodes(n_elements: int) -> list[int]:
    """0-based node indices of the sensor positions in an n-element mesh."""
    if n_elements % N_ELEMENTS_APRIORI:
        raise InputError(f"n_elements must be a multiple of {N_ELEMENTS_APRIORI}, got {n_elements}")
    step = n_elements // N_ELEMENTS_APRIORI
    return [step * (i + 1) for i in range(N_ELEMENTS_APRIORI - 1)]


def truth_ratios(state: str, n_elements: int = N_ELEMENTS_TRUTH) -> np.ndarray:
    """I multipliers of the 20-element truth in ``state`` (array of 20)."""
    if state not in DAMAGE_STATES:
        raise InputError(f"damage state {state!r} unknown; known: {sorted(DAMAGE_STATES)}")
    ratios = np.ones(n_elements)
    for element, value in DAMAGE_STATES[state].items():
        ratios[element - 1] = value
    return ratios


def equivalent_ratios(state: str, n_elements: int = N_ELEMENTS_APRIORI) -> np.ndarray:
    """Truth ratio per a-priori element: mean of the truth ratios of its sub-elements."""
    fine = truth_ratios(state)
    return fine.reshape(n_elements, -1).mean(axis=1)


def _ratios_from(values: Mapping[str, float], n_elements: int) -> np.ndarray:
    return np.array([float(values[name]) for name in ratio_names(n_elements)])


# ---- OpenSees backend -------------------------------------------------------------------
def build_beam(values: Mapping[str, float], n_elements: int = N_ELEMENTS_APRIORI) -> dict:
    """Build the 2D beam in the OpenSees domain; ``values`` holds ``ratio_01`` ... (I multipliers)."""
    from framework.models.opensees import ops_module

    ops = ops_module()
    ratios = _ratios_from(values, n_elements)
    if np.any(ratios <= 0):
        raise ModelEvaluationError("non_positive_stiffness", f"I ratios {ratios.tolist()}")
    ops.model("basic", "-ndm", 2, "-ndf", 3)
    length_e_m = LENGTH_M / n_elements
    for i in range(n_elements + 1):
        ops.node(i + 1, i * length_e_m, 0.0)
        ops.fix(i + 1, 1, 1 if i in (0, n_elements) else 0, 0)
    ops.geomTransf("Linear", 1)
    mass_kg_per_m = DENSITY_KG_PER_M3 * AREA_M2
    for e in range(n_elements):
        ops.element(
            "elasticBeamColumn", e + 1, e + 1, e + 2, AREA_M2, YOUNG_PA, INERTIA_M4 * ratios[e], 1,
            "-mass", mass_kg_per_m,
        )  # fmt: skip
    return {"n_elements": n_elements}


def make_opensees_model(
    n_elements: int = N_ELEMENTS_APRIORI,
    n_modes: int = 7,
    lower: float = RATIO_LOWER,
    upper: float = RATIO_UPPER,
):
    """The beam as an :class:`~framework.models.opensees.OpenSeesModel` (n_elements in 10, 20, ...)."""
    from framework.models.opensees import OpenSeesModel

    nodes = _sensor_nodes(n_elements)
    _check_n_modes(n_modes, n_elements)
    return OpenSeesModel(
        build=functools.partial(build_beam, n_elements=n_elements),
        parameters=beam_parameters(n_elements, lower, upper),
        measured_dofs={label: (node + 1, 2) for label, node in zip(dof_labels(), nodes)},
        n_modes=n_modes,
        linear_parameters=tuple(ratio_names(n_elements)),
        name=f"beam{n_elements}_opensees",
    )


def _check_n_modes(n_modes: int, n_elements: int) -> None:
    if not 1 <= n_modes <= n_elements - 1:
        raise InputError(f"n_modes must be in [1, {n_elements - 1}] for {n_elements} elements, got {n_modes}")


# ---- numpy backend ----------------------------------------------------------------------
def element_stiffness(length_m: float, ei_n_m2: float) -> np.ndarray:
    """Euler-Bernoulli element stiffness on (v1, th1, v2, th2): EI/l^3 [[12, 6l, -12, 6l], ...]."""
    ell = length_m
    return (ei_n_m2 / ell**3) * np.array(
        [
            [12.0, 6 * ell, -12.0, 6 * ell],
            [6 * ell, 4 * ell**2, -6 * ell, 2 * ell**2],
            [-12.0, -6 * ell, 12.0, -6 * ell],
            [6 * ell, 2 * ell**2, -6 * ell, 4 * ell**2],
        ]
    )


@functools.lru_cache(maxsize=8)
def _unit_matrices(n_elements: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Per-element global stiffness blocks (n_e, n_dof, n_dof) at ratio 1 on the free DOFs.

    Free DOFs: vertical translations of interior nodes first (n_e - 1), then all rotations.
    Returns (blocks, translational indices, nodal mass).
    """
    length_e_m = LENGTH_M / n_elements
    n_nodes = n_elements + 1
    k_e = element_stiffness(length_e_m, YOUNG_PA * INERTIA_M4)
    # global numbering: v_i -> 2i, th_i -> 2i + 1; free order: interior v, then all th
    free = [2 * i for i in range(1, n_nodes - 1)] + [2 * i + 1 for i in range(n_nodes)]
    position = {g: j for j, g in enumerate(free)}
    blocks = np.zeros((n_elements, len(free), len(free)))
    for e in range(n_elements):
        dofs = [2 * e, 2 * e + 1, 2 * e + 2, 2 * e + 3]
        for a, ga in enumerate(dofs):
            for b, gb in enumerate(dofs):
                if ga in position and gb in position:
                    blocks[e, position[ga], position[gb]] += k_e[a, b]
    nodal_mass_kg = DENSITY_KG_PER_M3 * AREA_M2 * length_e_m
    return blocks, np.arange(n_nodes - 2), nodal_mass_kg


def beam_modes(ratios: np.ndarray, n_modes: int, n_elements: int | None = None):
    """Frequencies (n, n_modes) Hz and mass-normalized vertical shapes (n, n_e - 1, n_modes).

    ratios: (n, n_e) I multipliers. K = sum_e r_e K_e; the massless rotations are
    condensed statically, K_c = K_vv - K_vr K_rr^-1 K_rv, and K_c phi = omega^2 m phi is
    solved with the uniform lumped nodal mass m (batched ``numpy.linalg.eigh``).
    """
    ratios = np.atleast_2d(np.asarray(ratios, dtype=float))
    n_elements = n_elements or ratios.shape[1]
    blocks, _, nodal_mass_kg = _unit_matrices(n_elements)
    nv = n_elements - 1
    stiffness = np.einsum("be,eij->bij", ratios, blocks)
    k_vv = stiffness[:, :nv, :nv]
    k_vr = stiffness[:, :nv, nv:]
    k_rr = stiffness[:, nv:, nv:]
    condensed = k_vv - k_vr @ np.linalg.solve(k_rr, np.swapaxes(k_vr, 1, 2))
    condensed = 0.5 * (condensed + np.swapaxes(condensed, 1, 2))
    omega2, vectors = np.linalg.eigh(condensed / nodal_mass_kg)
    freqs_hz = np.sqrt(np.maximum(omega2[:, :n_modes], 0.0)) / (2.0 * math.pi)
    shapes = vectors[:, :, :n_modes] / math.sqrt(nodal_mass_kg)
    return freqs_hz, shapes, omega2[:, :n_modes]


@dataclass(frozen=True)
class BeamNumpyModel:
    """The beam of :func:`make_opensees_model` assembled in numpy, with a vectorized ``modal_batch``."""

    n_elements: int = N_ELEMENTS_APRIORI
    n_modes: int = 7
    parameters: ParameterSet = field(default_factory=beam_parameters)
    name: str = "beam_numpy"

    def __post_init__(self) -> None:
        _check_n_modes(self.n_modes, self.n_elements)
        if self.parameters.names != ratio_names(self.n_elements):
            raise InputError(
                f"parameters must be {ratio_names(self.n_elements)[:2]}... ({self.n_elements}), "
                f"got {self.parameters.names}"
            )

    @property
    def dofs(self) -> tuple[str, ...]:
        return dof_labels()

    def _rows(self) -> list[int]:
        # interior node k (1-based) is row k - 1 of the translational block
        return [node - 1 for node in _sensor_nodes(self.n_elements)]

    def modal(self, theta: Mapping[str, float]) -> ModalResult:
        out = self.modal_batch([theta])[0]
        if isinstance(out, ModelEvaluationError):
            raise out
        return out

    def modal_batch(self, thetas: Sequence[Mapping[str, float]]) -> list:
        """Modes of many points at once; a failed point is returned as ModelEvaluationError."""
        if not thetas:
            return []
        ratios = np.array([_ratios_from(full_theta(self.parameters, t), self.n_elements) for t in thetas])
        bad = np.any(~np.isfinite(ratios) | (ratios <= 0), axis=1)
        out: list = [None] * len(thetas)
        good = np.flatnonzero(~bad)
        for i in np.flatnonzero(bad):
            out[i] = ModelEvaluationError("non_positive_stiffness", f"I ratios {ratios[i].tolist()}")
        if good.size:
            freqs, shapes, omega2 = beam_modes(ratios[good], self.n_modes, self.n_elements)
            rows = self._rows()
            for j, i in enumerate(good):
                out[i] = ModalResult(freqs[j], shapes[j][rows, :], self.dofs,
                                     meta={"omega2": omega2[j], "eigenvectors": shapes[j]})
        return out

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
        """Exact derivatives of the modes with respect to the I ratios (Nelson's method).

        K = sum_e r_e K_e is linear in the ratios (dK/dr_e = K_e, dM = 0) on the free DOFs
        [interior vertical translations, rotations]; M = diag(m, 0) is singular (massless
        rotations), which Nelson's method handles; the rotations of a mode are recovered
        from its translations by static condensation, phi_r = -K_rr^-1 K_rv phi_v.
        ``result``: this model's ModalResult at theta (else the modes are computed here).
        """
        names = list(self.parameters.names if parameters is None else parameters)
        cols = [self.parameters.names.index(n) for n in names]
        extra = 0
        if result is None or "eigenvectors" not in result.meta:
            result, extra = self.modal(theta), 1
        lam = np.asarray(result.meta["omega2"], float)
        modes = np.arange(lam.size) if modes is None else np.asarray(modes, dtype=int)
        check_separated(lam, modes, close_rtol)
        ratios = _ratios_from(full_theta(self.parameters, theta), self.n_elements)
        blocks, _, nodal_mass_kg = _unit_matrices(self.n_elements)
        nv = self.n_elements - 1
        K = np.einsum("e,eij->ij", ratios, blocks)
        M = np.diag(np.r_[np.full(nv, nodal_mass_kg), np.zeros(K.shape[0] - nv)])
        phi_v = np.asarray(result.meta["eigenvectors"], float)[:, modes]
        phi = np.vstack([phi_v, -np.linalg.solve(K[nv:, nv:], K[nv:, :nv] @ phi_v)])
        phi = normalize_mass(M, phi)
        dK_phi = np.einsum("eij,jm->ime", blocks[cols], phi)
        dlam, dphi, n_fact = eigen_derivatives(K, M, lam[modes], phi, dK_phi)
        return ModalDerivatives(modes, tuple(names), dlam, dphi[self._rows()], n_fact + extra)

    def geometry(self, theta: Mapping[str, float], shapes=None):
        """How its modes are drawn: its OpenSees twin (the same beam, read from the built domain)."""
        p = self.parameters
        return make_opensees_model(self.n_elements, self.n_modes, float(p.lower[0]), float(p.upper[0]))


# ---- registry entry points ----------------------------------------------------------------
def make_model(
    mesh: str = "apriori",
    backend: str = "numpy",
    n_modes: int = 7,
    lower: float = RATIO_LOWER,
    upper: float = RATIO_UPPER,
):
    """The beam model: mesh "apriori" (10 elements) or "truth" (20); backend "numpy" or "opensees"."""
    meshes = {"apriori": N_ELEMENTS_APRIORI, "truth": N_ELEMENTS_TRUTH}
    if mesh not in meshes:
        raise InputError(f"beam mesh {mesh!r} unknown; use one of {sorted(meshes)}")
    n_elements = meshes[mesh]
    if backend == "numpy":
        return BeamNumpyModel(
            n_elements, n_modes, beam_parameters(n_elements, lower, upper), name=f"beam{n_elements}_numpy"
        )
    if backend == "opensees":
        return make_opensees_model(n_elements, n_modes, lower, upper)
    raise InputError(f"beam backend {backend!r} unknown; use 'numpy' or 'opensees'")


def truth_modes(state: str, n_modes: int = 5, backend: str = "numpy", mesh: str = "truth") -> ModalResult:
    """Noise-free modes of a damage state.

    mesh "truth": the 20-element truth (the SPEC case, with discretization error against
    the 10-element model); mesh "apriori": the 10-element model at the equivalent ratios
    (no discretization error; isolates the optimizer's error from the model's).
    """
    model = make_model(mesh, backend=backend, n_modes=n_modes)
    n_elements = len(model.parameters)
    ratios = truth_ratios(state) if n_elements == N_ELEMENTS_TRUTH else equivalent_ratios(state)
    return model.modal(dict(zip(ratio_names(n_elements), ratios)))


def measured(case: str = "base", noise_pct: float = 0.0, seed: int = 0, n_modes: int = 5, mesh: str = "truth"):
    """Simulated measurement of a damage state: ``case`` in intact/state1/state2 ("base" = state1).

    ``case`` "source_state1"/"source_state2": the source's stated damaged frequencies
    (:data:`SOURCE_DAMAGED_FREQUENCIES_HZ`) with the noise-free shapes of the intact truth
    (used to check which truth reproduces them; the shapes only pair the modes).

    First ``n_modes`` frequencies of the 20-element truth (noise-free) and shapes at the
    9 sensor DOFs with multiplicative noise phi (1 + a eps), eps ~ U[-1, 1], a = noise_pct/100
    (see :func:`framework.damage.estimation.noisy_measurement`). ``mesh="apriori"`` simulates with the
    10-element model instead (see :func:`truth_modes`).
    """
    from framework.damage.estimation import noisy_measurement

    if case in ("source_state1", "source_state2"):
        from framework.measured.modes import MeasuredModes

        freqs = SOURCE_DAMAGED_FREQUENCIES_HZ[case.removeprefix("source_")]
        if not 1 <= n_modes <= len(freqs):
            raise InputError(f"n_modes must be in [1, {len(freqs)}] for case {case!r}, got {n_modes}")
        intact = truth_modes("intact", n_modes, mesh="truth")
        return MeasuredModes(frequencies_hz=np.array(freqs[:n_modes]), dofs=intact.dofs,
                             shapes=intact.shapes[:, :n_modes].copy(),
                             labels=tuple(f"bending {j + 1}" for j in range(n_modes)),
                             name=f"beam_{case}", source=f"SPEC 7:{case}")
    state = "state1" if case == "base" else case
    modes = truth_modes(state, n_modes, mesh=mesh)
    name = f"beam_{state}_{mesh}_noise{noise_pct:g}_seed{seed}"
    return noisy_measurement(modes, noise_pct / 100.0, seed, name=name)
