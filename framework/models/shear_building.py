"""Shear building: n lumped floor masses connected by inter-storey springs.

Storey i (i = 1..n, storey 1 between the ground and floor 1) has stiffness
k_i = k_i,0 (1 + alpha_i); its element matrix E_i couples floors i-1 and i:

    E_1 = e_1 e_1^T,   E_i = (e_i - e_{i-1})(e_i - e_{i-1})^T   (i > 1),
    K = sum_i (1 + alpha_i) k_i,0 E_i,    M = diag(m_1 .. m_n).

Any consistent unit system works (the four-storey benchmark uses lbf, in, s: masses in
lbf s^2/in, stiffnesses in lbf/in). Built on :class:`framework.models.matrix.MatrixModel`
with one updating parameter ``alpha_i`` per storey, DOFs labelled ``floor1`` .. ``floorN``;
exact modal derivatives (dK/dalpha_i = k_i,0 E_i) come with it (``modal_derivatives``).
Its modes are drawn as floors stacked one storey apart (:meth:`ShearBuilding.geometry`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from framework.core.errors import InputError
from framework.core.parameters import Parameter, ParameterSet
from framework.models.geometry import ModelShapes
from framework.models.matrix import MatrixModel


class ShearBuilding(MatrixModel):
    """A :class:`MatrixModel` whose DOFs are the floors' lateral displacements, floor i = DOF i - 1."""

    def geometry(self, theta: Mapping[str, float], shapes: ModelShapes) -> ModelShapes:
        """Floors stacked one storey apart (z in storeys), moving in x; the ground at z = 0;
        sensor points at the measured floors."""
        phi = np.asarray(self.modal(theta).meta["eigenvectors"], float)
        n = phi.shape[0]
        shapes.length_unit = "storey"
        shapes.node_tags = np.arange(0, n + 1)
        shapes.coords = np.zeros((n + 1, 3))
        shapes.coords[:, 2] = np.arange(n + 1)
        U = np.zeros((n + 1, 3, phi.shape[1]))
        U[1:, 0, :] = phi
        shapes.node_shapes = U[:, :, : shapes.frequencies_hz.size]
        shapes.elements = [(i, (i - 1, i), "storey") for i in range(1, n + 1)]
        floors = [int(self.dof_index[self.dofs.index(d)]) + 1 for d in shapes.dofs]
        shapes.points = [f"floor {f}" for f in floors]
        shapes.point_coords = shapes.coords[floors]
        shapes.T = np.zeros((len(floors), 3, len(floors)))
        for p in range(len(floors)):
            shapes.T[p, 0, p] = 1.0
        return shapes


def storey_matrices(n_floors: int) -> list[np.ndarray]:
    """Unit element matrices E_1..E_n of the storeys (see module docstring)."""
    out = []
    for i in range(n_floors):
        e = np.zeros(n_floors)
        e[i] = 1.0
        if i > 0:
            e[i - 1] = -1.0
        out.append(np.outer(e, e))
    return out


def make_shear_building(
    masses: Sequence[float],
    stiffnesses: Sequence[float],
    *,
    measured_floors: Sequence[int] | None = None,
    alpha_bounds: tuple[float, float] = (-1.0, 1.0),
    n_modes: int | None = None,
    name: str = "shear_building",
) -> ShearBuilding:
    """Shear-building model; measured_floors are 1-based (default: all floors)."""
    m = np.asarray(masses, dtype=float)
    k = np.asarray(stiffnesses, dtype=float)
    if m.ndim != 1 or m.size == 0 or k.shape != m.shape:
        raise InputError(f"masses ({m.size}) and stiffnesses ({k.size}) must be equal-length lists")
    if np.any(m <= 0) or not np.all(np.isfinite(m)):
        raise InputError(f"masses must be finite and > 0, got {m.tolist()}")
    if np.any(k <= 0) or not np.all(np.isfinite(k)):
        raise InputError(f"stiffnesses must be finite and > 0, got {k.tolist()}")
    lo, hi = alpha_bounds
    if not lo < 0.0 < hi:
        raise InputError(f"alpha_bounds must contain 0 strictly inside, got {alpha_bounds!r}")
    n = m.size
    floors = list(range(1, n + 1)) if measured_floors is None else [int(f) for f in measured_floors]
    bad = [f for f in floors if not 1 <= f <= n]
    if bad:
        raise InputError(f"measured_floors: floor(s) {bad} outside 1..{n}")
    params = ParameterSet(
        Parameter(f"alpha_{i + 1}", 0.0, lo, hi, "-", f"relative change of storey {i + 1} stiffness") for i in range(n)
    )
    parts = [ki * E for ki, E in zip(k, storey_matrices(n))]
    return ShearBuilding(
        parts,
        np.diag(m),
        params,
        {f"floor{f}": f - 1 for f in floors},
        n_modes=n if n_modes is None else n_modes,
        solver="condensation",
        name=name,
    )
