"""Effect catalogue of the simply supported beam (SPEC 7 geometry, 10-element mesh).

Model under test: the 10-element pinned-pinned Euler-Bernoulli beam of
:mod:`framework.structures.beam.model` (same element matrices, lumped mass, sensors at the 9
interior nodes) with one base parameter, ``EI_ratio`` (a global I multiplier, bounds
0.7-1.3: the uncertainty of E and of the cracked section).

Candidate effects:

- ``support_rotational_restraint``: equal rotational springs at both supports (bolted or
  grouted bearings are not ideal pins). Parameter ``support_fixity`` gamma in [0, 0.95],
  the fixity factor k_rot = 3 gamma EI_0 / (L (1 - gamma)) (0 = pin, 1 = clamp).
- ``localized_stiffness_loss``: one element (variant ``e01`` ... ``e10``) keeps only
  (1 - d) of its I. Parameter ``stiffness_loss`` d in [0, 0.8]. Searching the 10
  elements costs 2 ln 10 BIC (see :mod:`framework.diagnosis.score`).
- ``midspan_mass``: a non-structural point mass at midspan (equipment, a sensor rack),
  parameter ``midspan_mass_ratio`` (mass / beam mass) in [0, 0.5].

Solution: K = sum_e r_e K_e + rotational springs; the massless rotations are condensed
statically (K_c = K_vv - K_vr K_rr^-1 K_rv) and K_c phi = omega^2 M phi solved with
``scipy.linalg.eigh`` (M diagonal, lumped).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from scipy.linalg import eigh

from framework.core.errors import ModelEvaluationError
from framework.core.parameters import Parameter, ParameterSet
from framework.diagnosis.effects import Catalogue, Effect
from framework.models.base import ModalResult, full_theta
from framework.structures.beam.model import (
    AREA_M2,
    DENSITY_KG_PER_M3,
    INERTIA_M4,
    LENGTH_M,
    YOUNG_PA,
    dof_labels,
    element_stiffness,
)

N_ELEMENTS = 10
N_MODES_MODEL = 7
N_MODES_MEASURED = 5
ELEMENT_VARIANTS = tuple(f"e{i + 1:02d}" for i in range(N_ELEMENTS))

BASE_PARAMETERS = ParameterSet([Parameter("EI_ratio", 1.0, 0.7, 1.3, "-", "global bending stiffness multiplier")])

EFFECTS = {
    "support_rotational_restraint": Effect(
        "support_rotational_restraint",
        "equal rotational springs at both supports (fixity factor gamma)",
        (Parameter("support_fixity", 0.0, 0.0, 0.95, "-", "fixity factor: k_rot = 3 gamma EI / (L (1 - gamma))"),),
        hidden_values={"support_fixity": (0.3, 0.6)},
    ),
    "localized_stiffness_loss": Effect(
        "localized_stiffness_loss",
        "loss of a fraction d of I in one element (variant = element)",
        (Parameter("stiffness_loss", 0.0, 0.0, 0.8, "-", "fraction of I lost in the element"),),
        variants=ELEMENT_VARIANTS,
        hidden_values={"stiffness_loss": (0.3, 0.5)},
        hidden_variants=ELEMENT_VARIANTS[1:-1],
    ),
    "midspan_mass": Effect(
        "midspan_mass",
        "non-structural point mass at midspan",
        (Parameter("midspan_mass_ratio", 0.0, 0.0, 0.5, "-", "point mass / beam mass"),),
        hidden_values={"midspan_mass_ratio": (0.1, 0.2)},
    ),
}


def rotational_spring_n_m(fixity: float) -> float:
    """k_rot = 3 gamma EI_0 / (L (1 - gamma)) for fixity factor gamma (Monforton & Wu)."""
    return 3.0 * fixity * YOUNG_PA * INERTIA_M4 / (LENGTH_M * (1.0 - fixity))


@dataclass(frozen=True)
class BeamWithEffects:
    """The 10-element beam with the ``active`` effects ({name: variant})."""

    active: tuple[tuple[str, str], ...] = ()
    n_modes: int = N_MODES_MODEL

    @property
    def parameters(self) -> ParameterSet:
        items = list(BASE_PARAMETERS)
        for name, _ in self.active:
            items.extend(EFFECTS[name].parameters)
        return ParameterSet(items)

    @property
    def name(self) -> str:
        return "beam+" + "+".join(f"{n}[{v}]" if v else n for n, v in self.active) if self.active else "beam"

    @property
    def dofs(self) -> tuple[str, ...]:
        return dof_labels()

    def modal(self, theta: Mapping[str, float]) -> ModalResult:
        v = full_theta(self.parameters, theta)
        act = dict(self.active)
        ratios = np.full(N_ELEMENTS, v["EI_ratio"])
        if "localized_stiffness_loss" in act:
            e = ELEMENT_VARIANTS.index(act["localized_stiffness_loss"])
            ratios[e] *= 1.0 - v["stiffness_loss"]
        if np.any(ratios <= 0):
            raise ModelEvaluationError("non_positive_stiffness", f"I ratios {ratios.tolist()}")
        k_rot = rotational_spring_n_m(v["support_fixity"]) if "support_rotational_restraint" in act else 0.0
        le = LENGTH_M / N_ELEMENTS
        n_nodes = N_ELEMENTS + 1
        K = np.zeros((2 * n_nodes, 2 * n_nodes))
        ke = element_stiffness(le, YOUNG_PA * INERTIA_M4)
        for e in range(N_ELEMENTS):
            d = slice(2 * e, 2 * e + 4)
            K[d, d] += ratios[e] * ke
        K[1, 1] += k_rot
        K[2 * N_ELEMENTS + 1, 2 * N_ELEMENTS + 1] += k_rot
        tv = [2 * i for i in range(1, n_nodes - 1)]
        tr = [2 * i + 1 for i in range(n_nodes)]
        kvv, kvr, krr = K[np.ix_(tv, tv)], K[np.ix_(tv, tr)], K[np.ix_(tr, tr)]
        kc = kvv - kvr @ np.linalg.solve(krr, kvr.T)
        kc = 0.5 * (kc + kc.T)
        m_node = DENSITY_KG_PER_M3 * AREA_M2 * le
        mass = np.full(len(tv), m_node)
        if "midspan_mass" in act:
            mass[len(tv) // 2] += v["midspan_mass_ratio"] * DENSITY_KG_PER_M3 * AREA_M2 * LENGTH_M
        w2, phi = eigh(kc, np.diag(mass), subset_by_index=[0, self.n_modes - 1])
        if np.any(w2 <= 0):
            raise ModelEvaluationError("indefinite_matrix", f"eigenvalues {w2.tolist()}")
        return ModalResult(np.sqrt(w2) / (2 * math.pi), phi, self.dofs)


def make_model(active: Mapping[str, str], n_modes: int = N_MODES_MODEL) -> BeamWithEffects:
    order = [n for n in EFFECTS if n in active]
    return BeamWithEffects(tuple((n, active[n]) for n in order), n_modes)


def catalogue(n_modes: int = N_MODES_MODEL, n_measured_modes: int = N_MODES_MEASURED) -> Catalogue:
    """The beam's catalogue (model under test: pinned beam, global EI only)."""
    return Catalogue(
        structure="beam",
        base_parameters=BASE_PARAMETERS,
        effects=EFFECTS,
        factory=make_model,
        n_measured_modes=n_measured_modes,
        options={"n_modes": n_modes},
        description="10-element simply supported beam (SPEC 7), 5 modes at 9 vertical DOFs",
    )
