"""Fast evaluation path of the bridge model: OpenSees gravity, numpy/scipy eigen solution.

The plain path (:class:`~framework.models.opensees.OpenSeesModel`) spends most of its
time in OpenSees' ARPACK solution of ~100 modes and in reading eigenvectors node by node.
This path keeps OpenSees for what is nonlinear (the build and the gravity analysis of the
corotational cable chains) and replaces the rest with linear algebra on matrices that are
exact for this model:

- the stiffness of every element except the cables is linear in the updating ratios, so
  K_lin(theta) = K_0 + sum_p (theta_p - 1) K_p with K_0 and the K_p extracted once from
  OpenSees (:func:`~framework.models.opensees_matrices.static_stiffness`: ``printA`` of a
  ``FullGeneral`` system, Transformation constraints; unit perturbations of K_y_deck,
  K_x_deck, K_t_deck, K_bearing);
- the cable chains' tangent is assembled per evaluation from the gravity state read from
  OpenSees, with the corotational truss tangent
  k_e = (E A / L_0) n n' + (N / L_n) (I - n n')  (n current unit vector, L_n current
  length, N axial force); anchors on rigid links map through u_s = u_m + rot_m x r;
- the bridge is symmetric about the pylon plane and the deck's vertical centre plane,
  and so are all six parameters and the gravity state; in the symmetry-adapted basis
  of the two mirrors (four classes: symmetric/antisymmetric about each plane) K and M
  are block diagonal, so four problems of ~155 DOFs replace one of 624. The blocks of
  K_0 and K_p are projected once; the cable part per evaluation. If the cable state is
  not mirror-symmetric (checked per evaluation, relative 1e-9) the full problem is
  solved instead;
- the massless DOFs (rotations without inertia) are condensed statically (exact for
  the eigenvalue problem when those DOFs carry no mass):
  K_r = K_mm - K_ms K_ss^-1 K_sm, then the standard symmetric problem
  M^-1/2 K_r M^-1/2 y = omega^2 y is solved densely (LAPACK evd) up to f_max.

Why hand-written: OpenSees offers no cheap way to export its tangent per evaluation
(printA on a dense system costs more than the whole fast evaluation), and only the
cable tangent changes with the gravity state. The agreement with the plain path is
checked by tests/test_bridge_fast.py and benchmarks/bench_bridge.py.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from framework.core.errors import ModelEvaluationError
from framework.core.modal_derivatives import (
    CLOSE_EIGENVALUE_RTOL,
    ModalDerivatives,
    check_separated,
    eigen_derivatives,
    normalize_mass,
)
from framework.models.base import ModalResult, full_theta
from framework.models.eigen_solve import single_thread_blas
from framework.models.opensees import OpenSeesModel, ops_module, run_static
from framework.models.opensees_matrices import static_stiffness
from framework.structures.bridge.build import cable_tensions_from
from framework.structures.bridge.geometry import (
    ANCHOR_NODE0,
    CABLE_AREA_M2,
    CABLE_NODE0,
    DECK_LENGTH_M,
    E_CABLE_PA,
    GROUND_NODE0,
    N_DECK_ELEMENTS,
    PYLON_NODE0,
    PYLON_X_M,
    SENSOR_NODE0,
    deck_node,
)
from framework.structures.bridge.modes import MODE_TYPES, keep_deck_modes, node_groups

log = logging.getLogger(__name__)

#: parameters whose stiffness contribution is linear and extracted once
LINEAR_PARAMETERS = ("K_y_deck", "K_x_deck", "K_t_deck", "K_bearing")


@dataclass
class _Irrep:
    """One symmetry class: K_r = k0 + sum_p (theta_p - 1) k_param[p] + C' D C (dense n_r)."""

    k0: np.ndarray
    k_param: dict[str, np.ndarray]
    c_cable: np.ndarray  # (E, 6, n_c) = B_cable B_r restricted to its nonzero columns
    cable_cols: np.ndarray  # (n_c,) those columns
    n_mass: int  # massive columns first
    mass: np.ndarray  # (n_mass,)
    basis_master: np.ndarray  # (n_master, n_mass) dense, back-transformation


@dataclass
class _Operators:
    """Matrices and index maps extracted once per model.

    Equations are permuted so that the n_master equations with mass come first; the
    stiffness is stored as one sparse pattern (indptr, indices) with a data vector per term.
    """

    n_master: int
    indptr: np.ndarray
    indices: np.ndarray
    d0: np.ndarray  # data of the linear part at theta = 1 (cables removed)
    d_param: dict[str, np.ndarray]  # data of dK / dtheta_p
    mass: np.ndarray  # (n_master,) lumped masses
    b_cable: sp.csr_matrix  # (6 E, n) element-end translations from equations
    cable_elements: np.ndarray  # (E,) element tags
    cable_ends: np.ndarray  # (E, 2) node tags
    cable_nodes: np.ndarray  # nodes whose displacement is read
    coords: dict[int, np.ndarray]
    length0: np.ndarray  # (E,)
    group_eqs: dict[str, tuple[np.ndarray, np.ndarray]]  # group -> (equations, masses)
    deck_dir_eqs: np.ndarray  # (n_deck, 4) equations of ux, uy, uz, rx of spine nodes
    sensor_rows: list[tuple[int, int, float]]  # (eq of translation, eq of rx, y factor)
    irreps: list[_Irrep] | None = None  # symmetry-adapted blocks (None: no symmetry)
    cable_mirrors: list[tuple[np.ndarray, np.ndarray]] | None = None  # (element map, signs)

    def stiffness(self, values: Mapping[str, float], k3: np.ndarray) -> sp.csr_matrix:
        """K = K_0 + sum_p (theta_p - 1) K_p + K_cable(k3), sparse, permuted order."""
        data = self.d0.copy()
        for p, d in self.d_param.items():
            data += (float(values[p]) - 1.0) * d
        n = self.indptr.size - 1
        k_lin = sp.csr_matrix((data, self.indices, self.indptr), shape=(n, n))
        return k_lin + _cable_matrix(self.b_cable, k3)


def _translation_map(ops, node: int, master_of: Mapping[int, int], n_eq: int) -> np.ndarray:
    """(3, n_eq) map from equations to the node's translations (rigid-link slaves too)."""
    g = np.zeros((3, n_eq))
    if node in master_of:
        m = master_of[node]
        eq = ops.nodeDOFs(m)
        r = np.subtract(ops.nodeCoord(node), ops.nodeCoord(m))
        # u_s = u_m + rot_m x r
        cross = np.array([[0.0, r[2], -r[1]], [-r[2], 0.0, r[0]], [r[1], -r[0], 0.0]])
        for i in range(3):
            if eq[i] >= 0:
                g[i, eq[i]] += 1.0
            for j in range(3):
                if eq[3 + j] >= 0 and cross[i, j] != 0.0:
                    g[i, eq[3 + j]] += cross[i, j]
    else:
        eq = ops.nodeDOFs(node)
        for i in range(3):
            if eq[i] >= 0:
                g[i, eq[i]] = 1.0
    return g


def cable_tangent(xa, xb, length0, ea_n, force_n) -> np.ndarray:
    """(E, 3, 3) corotational truss tangents k = EA/L0 n n' + N/Ln (I - n n')."""
    d = np.asarray(xb) - np.asarray(xa)
    ln = np.linalg.norm(d, axis=1)
    n = d / ln[:, None]
    nn = n[:, :, None] * n[:, None, :]
    eye = np.eye(3)[None, :, :]
    return (ea_n / length0)[:, None, None] * nn + (force_n / ln)[:, None, None] * (eye - nn)


def _element_blocks(k3: np.ndarray) -> np.ndarray:
    """(E, 6, 6) element matrices [[k, -k], [-k, k]] from (E, 3, 3) tangents."""
    top = np.concatenate([k3, -k3], axis=2)
    bottom = np.concatenate([-k3, k3], axis=2)
    return np.concatenate([top, bottom], axis=1)


def _cable_matrix(b: sp.csr_matrix, k3: np.ndarray) -> sp.csr_matrix:
    """K_cable = B' diag(k_e6) B with k_e6 = [[k, -k], [-k, k]] per element (E, 3, 3)."""
    blocks = _element_blocks(k3)
    e = blocks.shape[0]
    d = sp.bsr_matrix((blocks, np.arange(e), np.arange(e + 1)), shape=(6 * e, 6 * e))
    return (b.T @ d @ b).tocsr()


def extract_operators(plain: OpenSeesModel) -> _Operators:
    """Extract K_0, K_p, M and the index maps from OpenSees (5 builds, once per model).

    OpenSees forms the printed matrix at the state after its (linear) extraction step, so
    the cable tangent of that state is subtracted; the interior cable-node block of the
    remainder must vanish, which checks :func:`cable_tangent` against OpenSees.
    """
    ops = ops_module()
    base = dict(plain.fixed)
    base.update(full_theta(plain.parameters, {}))
    variants = [dict(base)] + [dict(base, **{p: base[p] + 1.0}) for p in LINEAR_PARAMETERS]
    linear = []
    dofs_ref = None
    data: dict = {}
    try:
        for values in variants:
            ops.wipe()
            info = plain.build(values)
            a = static_stiffness(ops)
            eq_map = {n: tuple(ops.nodeDOFs(n)) for n in ops.getNodeTags()}
            if dofs_ref is None:
                dofs_ref = eq_map
                data = _index_data(ops, info, a.shape[0])
            elif eq_map != dofs_ref:  # pragma: no cover - topology does not change
                raise ModelEvaluationError("model_error", "equation numbering changed between builds")
            k_cab = _cable_matrix(data["b_cable"], _current_cable_tangent(ops, data, values)).toarray()
            k_lin = a - k_cab
            interior = data["interior_eqs"]
            if interior.size:
                block = np.ix_(interior, interior)
                resid = np.abs(k_lin[block]).max() / np.abs(k_cab[block]).max()
                if resid > 1e-9:
                    raise ModelEvaluationError(
                        "model_error", f"cable tangent does not match OpenSees (relative {resid:.2e})"
                    )
            linear.append(k_lin)
    finally:
        ops.wipe()
    data.pop("interior_eqs")
    return _permuted(data, linear)


def _permuted(data: dict, linear: list[np.ndarray]) -> _Operators:
    """Permute equations (massive first) and store the stiffness terms on one pattern."""
    mass = data.pop("mass")
    master = np.flatnonzero(mass > 0.0)
    order = np.concatenate([master, np.flatnonzero(mass == 0.0)])
    inv = np.empty_like(order)
    inv[order] = np.arange(order.size)
    mats = [m[np.ix_(order, order)] for m in linear]
    k_param = [m - mats[0] for m in mats[1:]]
    pattern = sp.csr_matrix(sum(np.abs(m) for m in [mats[0], *k_param]) != 0.0)
    rows = np.repeat(np.arange(order.size), np.diff(pattern.indptr))
    cols = pattern.indices
    data["b_cable"] = data["b_cable"][:, order].tocsr()
    data["group_eqs"] = {g: (inv[eq], m) for g, (eq, m) in data["group_eqs"].items()}
    data["deck_dir_eqs"] = inv[data["deck_dir_eqs"]]
    data["sensor_rows"] = [(int(inv[t]), int(inv[r]) if r >= 0 else -1, y) for t, r, y in data["sensor_rows"]]
    data["irreps"] = _symmetry(data.pop("mirrors"), order, inv, mass, master, mats, k_param, data["b_cable"])
    data["cable_mirrors"] = _cable_mirrors(data) if data["irreps"] is not None else None
    return _Operators(
        n_master=int(master.size),
        indptr=pattern.indptr.copy(),
        indices=pattern.indices.copy(),
        d0=mats[0][rows, cols],
        d_param={p: k[rows, cols] for p, k in zip(LINEAR_PARAMETERS, k_param)},
        mass=mass[master],
        **data,
    )


def _symmetry(mirrors, order, inv, mass, master, mats, k_param, b_cable) -> list[_Irrep] | None:
    """Symmetry-adapted blocks of the stiffness terms.

    With the two mirrors S_x, S_y (signed permutations, S^2 = I, commuting) the projectors
    P_ab = (I + a S_x)(I + b S_y) / 4, a, b = +-1, split the space into four orthogonal
    invariant subspaces; K and M commuting with S_x and S_y are block diagonal in the
    bases B_r = normalized distinct columns of P_ab, and the eigenproblem splits into four
    problems of ~1/4 the size. None when the mesh, the masses or a stiffness term is not
    mirror-symmetric (then the full problem is solved).
    """
    if mirrors is None:
        return None
    n = order.size
    mass_perm = mass[order]
    mats_s = {}
    for axis, (target, sign) in mirrors.items():
        rows = inv[target[order]]
        s_mat = sp.csr_matrix((sign[order], (rows, np.arange(n))), shape=(n, n))
        if not np.allclose(mass_perm[rows], mass_perm):
            return None
        for m in [mats[0], *k_param]:
            if np.abs(s_mat @ m @ s_mat.T - m).max() > 1e-10 * np.abs(mats[0]).max():
                return None
        mats_s[axis] = s_mat
    eye = sp.identity(n, format="csr")
    n_master = master.size
    # orbit representatives: the smallest equation of {i, S_x i, S_y i, S_x S_y i}
    tx = np.asarray(abs(mats_s["x"]).argmax(axis=0)).ravel()
    ty = np.asarray(abs(mats_s["y"]).argmax(axis=0)).ravel()
    reps = np.unique(np.minimum.reduce([np.arange(n), tx, ty, tx[ty]]))
    terms = [sp.csr_matrix(m) for m in [mats[0], *k_param]]
    irreps = []
    total = 0
    for a in (1.0, -1.0):
        for b_ in (1.0, -1.0):
            proj = ((eye + a * mats_s["x"]) @ (eye + b_ * mats_s["y"]) * 0.25).tocsc()[:, reps]
            proj.eliminate_zeros()
            proj = proj[:, np.flatnonzero(np.diff(proj.indptr) > 0)]  # orbits absent in this class
            norms = np.sqrt(np.asarray(proj.multiply(proj).sum(axis=0)).ravel())
            basis = (proj @ sp.diags(1.0 / norms)).tocsc()
            massive = np.asarray(abs(basis[:n_master]).sum(axis=0)).ravel() > 0
            basis = basis[:, np.concatenate([np.flatnonzero(massive), np.flatnonzero(~massive)])].tocsr()
            n_mass = int(massive.sum())
            projected = [(basis.T @ t @ basis).toarray() for t in terms]
            bm = basis[:n_master, :n_mass].toarray()
            irreps.append(
                _Irrep(
                    k0=projected[0],
                    k_param=dict(zip(LINEAR_PARAMETERS, projected[1:])),
                    **_cable_projection(b_cable @ basis),
                    n_mass=n_mass,
                    mass=(bm**2).T @ mass[master],
                    basis_master=bm,
                )
            )
            total += basis.shape[1]
    if total != n:  # pragma: no cover - defensive
        log.warning("symmetry-adapted bases incomplete (%d of %d); full eigen solution", total, n)
        return None
    return irreps


def _cable_projection(c: sp.spmatrix) -> dict:
    """Dense (E, 6, n_c) cable map on the columns of ``c`` that are not identically zero."""
    c = c.tocsc()
    cols = np.flatnonzero(np.diff(c.indptr) > 0)
    dense = c[:, cols].toarray()
    return {"c_cable": dense.reshape(-1, 6, cols.size), "cable_cols": cols}


def _cable_mirrors(data: dict) -> list[tuple[np.ndarray, np.ndarray]] | None:
    """For each mirror: the mirrored element of each cable element and the translation signs."""
    ends = data["cable_ends"]
    xyz = data["coords"]
    key = {frozenset((_point_key(xyz[i]), _point_key(xyz[j]))): e for e, (i, j) in enumerate(ends)}
    out = []
    for axis, signs in _MIRROR_SIGNS.items():
        perm = np.empty(len(ends), dtype=int)
        for e, (i, j) in enumerate(ends):
            mirrored = key.get(frozenset((_point_key(xyz[i], axis), _point_key(xyz[j], axis))))
            if mirrored is None:
                return None
            perm[e] = mirrored
        out.append((perm, np.array(signs[:3], dtype=float)))
    return out


def solve_irreps(values: Mapping[str, float], k3: np.ndarray, op: _Operators, omega2_max: float):
    """As :func:`solve_band`, block by block in the symmetry-adapted bases; phi = B_r phi_r."""
    blocks = _element_blocks(k3)
    omegas, phis = [], []
    for irrep in op.irreps:
        c = irrep.c_cable
        kc = c.reshape(-1, c.shape[2]).T @ np.matmul(blocks, c).reshape(-1, c.shape[2])
        k = irrep.k0.copy()
        for p, kp in irrep.k_param.items():
            k += (float(values[p]) - 1.0) * kp
        k[np.ix_(irrep.cable_cols, irrep.cable_cols)] += kc
        w, y = solve_dense(k, irrep.mass, omega2_max)
        omegas.append(w)
        phis.append(irrep.basis_master @ y)
    w = np.concatenate(omegas)
    idx = np.argsort(w)
    return w[idx], np.hstack(phis)[:, idx]


def is_symmetric_state(k3: np.ndarray, op: _Operators, rtol: float = 1e-9) -> bool:
    """True when every cable tangent equals its mirror image's: R k_e R = k_mirror(e)."""
    if op.irreps is None or op.cable_mirrors is None:
        return False
    scale = np.abs(k3).max()
    for perm, signs in op.cable_mirrors:
        mirrored = signs[None, :, None] * k3 * signs[None, None, :]
        if np.abs(mirrored - k3[perm]).max() > rtol * scale:
            return False
    return True


def _current_cable_tangent(ops, data: dict, values) -> np.ndarray:
    """Cable tangents (E, 3, 3) of the current OpenSees state."""
    disp = {int(n): np.asarray(ops.nodeDisp(int(n))[:3]) for n in data["cable_nodes"]}
    force = np.array([ops.eleResponse(int(e), "axialForce")[0] for e in data["cable_elements"]])
    ends = data["cable_ends"]
    xa = np.array([data["coords"][i] + disp[i] for i in ends[:, 0]])
    xb = np.array([data["coords"][j] + disp[j] for j in ends[:, 1]])
    ea = E_CABLE_PA * float(values["K_cable"]) * CABLE_AREA_M2
    return cable_tangent(xa, xb, data["length0"], np.full(force.size, ea), force)


#: sign of each DOF (ux, uy, uz, rx, ry, rz) under the mirror x -> 2 x_pylon - x and
#: y -> -y: translations flip along the normal, rotations (axial vectors) flip in-plane
_MIRROR_SIGNS = {"x": (-1, 1, 1, 1, -1, -1), "y": (1, -1, 1, -1, 1, -1)}


def _point_key(xyz, axis: str | None = None) -> tuple[float, float, float]:
    """Rounded coordinates (to 1 um) of a point or of its mirror image (axis "x" or "y")."""
    c = np.asarray(xyz, dtype=float).copy()
    if axis == "x":
        c[0] = 2.0 * PYLON_X_M - c[0]
    elif axis == "y":
        c[1] = -c[1]
    return tuple(float(v) + 0.0 for v in np.round(c, 6))


def _mirror_maps(ops, n_eq: int, master_of) -> dict[str, tuple[np.ndarray, np.ndarray]] | None:
    """Signed equation permutations of the two mirror symmetries of the bridge.

    For each mirror, (target, sign): u_eq[target[i]] = sign[i] u_eq[i] maps a displacement
    field onto its mirror image. None if some equation has no mirror (asymmetric mesh).
    """

    def kind(n: int) -> int:  # coincident nodes (bearings) differ in kind
        return int(np.searchsorted([PYLON_NODE0, GROUND_NODE0, ANCHOR_NODE0, CABLE_NODE0], n, "right"))

    owners: dict[tuple, int] = {}
    coords = {}
    for n in ops.getNodeTags():
        if n in master_of or (SENSOR_NODE0 <= n < CABLE_NODE0):
            continue  # rigid-link slaves have no equations of their own
        coords[n] = (ops.nodeCoord(n), kind(n))
        for d, eq in enumerate(ops.nodeDOFs(n)):
            if eq >= 0:
                owners[(n, d)] = eq
    by_xyz = {(_point_key(xyz), k): n for n, (xyz, k) in coords.items()}
    out = {}
    for axis, signs in _MIRROR_SIGNS.items():
        target = np.full(n_eq, -1)
        sign = np.zeros(n_eq)
        for (n, d), eq in owners.items():
            xyz, k = coords[n]
            m = by_xyz.get((_point_key(xyz, axis), k))
            if m is None or (m, d) not in owners:
                return None
            target[eq] = owners[(m, d)]
            sign[eq] = signs[d]
        if np.any(target < 0):
            return None
        out[axis] = (target, sign)
    return out


def _index_data(ops, info, n_eq: int) -> dict:
    master_of = {}
    for n in ops.getNodeTags():
        if ANCHOR_NODE0 <= n < CABLE_NODE0:
            x = ops.nodeCoord(n)[0]
            master_of[n] = deck_node(int(round(x / (DECK_LENGTH_M / N_DECK_ELEMENTS))))
    mirrors = _mirror_maps(ops, n_eq, master_of)
    mass = np.zeros(n_eq)
    for node, m in info.masses.items():
        eq = ops.nodeDOFs(node)
        for d, value in enumerate(m):
            if value != 0.0 and eq[d] >= 0:  # masses on fixed DOFs never move
                mass[eq[d]] += value
    elements, ends = [], []
    for cables in info.cable_elements.values():
        for cable in cables:
            for e in cable:
                elements.append(e)
                ends.append(ops.eleNodes(e))
    ends = np.array(ends, dtype=int)
    coords = {int(n): np.array(ops.nodeCoord(int(n))) for n in np.unique(ends)}
    length0 = np.array([np.linalg.norm(coords[j] - coords[i]) for i, j in ends])
    rows = []
    for i, j in ends:
        rows.append(_translation_map(ops, int(i), master_of, n_eq))
        rows.append(_translation_map(ops, int(j), master_of, n_eq))
    b_cable = sp.csr_matrix(np.vstack(rows))
    groups = {}
    for group, nodes in node_groups(info).items():
        eqs, ms = [], []
        for node in nodes:
            eq = ops.nodeDOFs(node)
            for d, value in enumerate(info.masses[node]):
                if value != 0.0 and eq[d] >= 0:
                    eqs.append(eq[d])
                    ms.append(value)
        groups[group] = (np.array(eqs, dtype=int), np.array(ms))
    deck_dir = np.array([ops.nodeDOFs(n)[:4] for n in info.deck_nodes], dtype=int)
    sensor_rows = []
    for label in info.sensor_dofs:
        spine, y = info.sensor_offsets[label]
        eq = ops.nodeDOFs(spine)
        if label.endswith("_uz"):
            sensor_rows.append((eq[2], eq[3], y))  # uz_edge = uz + rx * y
        else:
            sensor_rows.append((eq[1], -1, 0.0))  # uy_edge = uy (edge at spine level)
    interior = np.array([e for n in info.cable_nodes for e in ops.nodeDOFs(n)[:3] if e >= 0], dtype=int)
    return {
        "mirrors": mirrors,
        "mass": mass,
        "b_cable": b_cable,
        "cable_elements": np.array(elements, dtype=int),
        "cable_ends": ends,
        "cable_nodes": np.unique(ends),
        "coords": coords,
        "length0": length0,
        "group_eqs": groups,
        "deck_dir_eqs": deck_dir,
        "sensor_rows": sensor_rows,
        "interior_eqs": interior,
    }


class BridgeFastModel:
    """Fast bridge model with the same build, parameters and DOFs as the plain one.

    modal(theta): OpenSees build + gravity, then K(theta) from the extracted operators and
    the cable state, condensation of massless DOFs and a dense band eigen solution.
    """

    def __init__(self, plain: OpenSeesModel, *, deck_energy_min: float = 0.1, f_max_hz: float = 15.0):
        self.plain = plain
        self.deck_energy_min = float(deck_energy_min)
        self.f_max_hz = float(f_max_hz)
        self.name = plain.name + "_fast"
        self._operators: _Operators | None = None
        # same gravity analysis, sparse symmetric solver (twice as fast as UmfPack here; the
        # plain path cannot use it: OpenSees' eigen after a SparseSYM system fails)
        self.gravity = dataclasses.replace(plain.gravity, system="SparseSYM")

    @property
    def parameters(self):
        return self.plain.parameters

    @property
    def dofs(self) -> tuple[str, ...]:
        return self.plain.dofs

    def __getstate__(self):
        state = dict(self.__dict__)
        state["_operators"] = None  # rebuilt lazily in the worker
        return state

    def geometry(self, theta: Mapping[str, float], shapes=None) -> OpenSeesModel:
        """How its modes are drawn: the plain model's built OpenSees domain (same build)."""
        return self.plain

    @property
    def operators(self) -> _Operators:
        if self._operators is None:
            self._operators = extract_operators(self.plain)
        return self._operators

    def _values(self, theta: Mapping[str, float]) -> dict:
        values = dict(self.plain.fixed)
        values.update(full_theta(self.plain.parameters, theta))
        return values

    def _gravity_state(self, values: Mapping[str, float]):
        """OpenSees build and gravity analysis: (build info, cable tangents (E, 3, 3), cable forces)."""
        op = self.operators
        ops = ops_module()
        ops.wipe()
        try:
            info = self.plain.build(values)
            run_static(ops, self.gravity)
            k3 = _current_cable_tangent(ops, op.__dict__, values)
            force = np.array([ops.eleResponse(int(e), "axialForce")[0] for e in op.cable_elements])
        finally:
            ops.wipe()
        return info, k3, force

    def modal(self, theta: Mapping[str, float]) -> ModalResult:
        """Deck modes at ``theta``; meta keeps omega2 of every computed mode, and for
        :meth:`modal_derivatives` the kept modes' mass-normalized equation-space shapes
        (``eigenvectors``, n_master x kept) and the cable tangents (``cable_tangent``)."""
        op = self.operators
        values = self._values(theta)
        info, k3, force = self._gravity_state(values)
        tension = cable_tensions_from(force, info)
        omega2_max = (2.0 * math.pi * self.f_max_hz) ** 2
        with single_thread_blas():
            if is_symmetric_state(k3, op):
                omega2, phi = solve_irreps(values, k3, op, omega2_max)
            else:
                omega2, phi = solve_band(op.stiffness(values, k3), op.mass, omega2_max)
        freqs = np.sqrt(np.maximum(omega2, 0.0)) / (2.0 * math.pi)
        shapes = self._sensor_shapes(phi)
        shares = energy_shares_eq(phi, op)
        meta = {"omega2": omega2, "cable_tension_n": tension, "target_tension_n": dict(info.target_tension_n)}
        result = keep_deck_modes(freqs, shapes, self.dofs, shares, self.deck_energy_min, meta)
        keep = result.mode_info["model_mode"] - 1
        return dataclasses.replace(result, meta={**result.meta, "eigenvectors": phi[:, keep], "cable_tangent": k3})

    def _sensor_shapes(self, phi: np.ndarray) -> np.ndarray:
        """Shapes at the sensors from equation-space shapes (n_master, ...): u_t + y r_x."""
        rows = self.operators.sensor_rows
        return np.array([phi[t] + (y * phi[r] if r >= 0 else 0.0) for t, r, y in rows]).reshape(
            (len(rows),) + phi.shape[1:]
        )

    # ---- derivatives ------------------------------------------------------------------
    #: relative step of the central differences of the cable tangents
    CABLE_STEP = 1e-4

    def derivative_cost(self, n_modes: int, n_params: int) -> int:
        """Eigen-solve equivalents of :meth:`modal_derivatives`: one factorization per mode, one of
        the massless block, and two re-assemblies (OpenSees build + gravity) per parameter."""
        return int(n_modes) + 1 + 2 * int(n_params)

    def modal_derivatives(
        self,
        theta: Mapping[str, float],
        result: ModalResult | None = None,
        *,
        parameters: Sequence[str] | None = None,
        modes: Sequence[int] | None = None,
        close_rtol: float = CLOSE_EIGENVALUE_RTOL,
    ) -> ModalDerivatives:
        """Derivatives of the deck modes ``modes`` (indices into the ModalResult) by Nelson's method
        on the full equation space (singular M: massless DOFs).

        dK/dtheta_p = K_p (extracted, exact: the linear elements are linear in their ratio)
        + B' k_cable(dk3/dtheta_p) B, the change of the cable tangent through the gravity
        state, by central differences of the ASSEMBLED cable tangents at theta_p +- h
        (h = CABLE_STEP theta_p; an OpenSees build and gravity analysis each, no eigen
        solution). Every parameter moves the gravity state (deck stiffness and bearings
        change the sag), so every parameter gets this term. dM = 0.
        """
        op = self.operators
        names = list(self.parameters.names if parameters is None else parameters)
        unknown = [n for n in names if n not in self.parameters.names]
        if unknown:
            raise KeyError(f"unknown parameter(s) {unknown}; known: {self.parameters.names}")
        extra = 0
        if result is None or "eigenvectors" not in result.meta:
            result, extra = self.modal(theta), 1
        modes = np.arange(result.n_modes) if modes is None else np.asarray(modes, dtype=int)
        omega2_all = np.asarray(result.meta["omega2"], float)
        computed = np.asarray(result.mode_info["model_mode"], dtype=int)[modes] - 1
        check_separated(omega2_all, computed, close_rtol)
        values = self._values(theta)
        k3 = np.asarray(result.meta["cable_tangent"], float)
        K = op.stiffness(values, k3).tocsc()
        nm = op.n_master
        phi_m = np.asarray(result.meta["eigenvectors"], float)[:, modes]
        try:
            lu = spla.splu(K[nm:, nm:].tocsc())
        except RuntimeError as exc:
            raise ModelEvaluationError("singular_matrix", f"massless block: {exc}") from exc
        phi = np.vstack([phi_m, -lu.solve(np.asarray(K[nm:, :nm] @ phi_m))])
        M = sp.diags(np.r_[op.mass, np.zeros(K.shape[0] - nm)]).tocsc()
        phi = normalize_mass(M, phi)
        n = K.shape[0]
        dK_phi = np.empty((n, modes.size, len(names)))
        for j, name in enumerate(names):
            h = self.CABLE_STEP * max(1.0, abs(values[name]))
            dk3 = (self._gravity_state({**values, name: values[name] + h})[1]
                   - self._gravity_state({**values, name: values[name] - h})[1]) / (2.0 * h)
            dK = _cable_matrix(op.b_cable, dk3)
            if name in op.d_param:
                dK = dK + sp.csr_matrix((op.d_param[name], op.indices, op.indptr), shape=(n, n))
            dK_phi[:, :, j] = dK @ phi
        with single_thread_blas():
            dlam, dphi, n_fact = eigen_derivatives(K, M, omega2_all[computed], phi, dK_phi)
        return ModalDerivatives(modes, tuple(names), dlam, self._sensor_shapes(dphi[:nm]),
                                n_fact + 1 + 2 * len(names) + extra)


def solve_dense(k: np.ndarray, mass: np.ndarray, omega2_max: float):
    """Dense version of :func:`solve_band` (massive DOFs first, the rest condensed)."""
    nm = mass.size
    kr = k[:nm, :nm]
    if k.shape[0] > nm:
        try:
            c = sla.cho_factor(k[nm:, nm:], check_finite=False)
        except np.linalg.LinAlgError as exc:
            raise ModelEvaluationError("singular_matrix", f"massless block: {exc}") from exc
        ksm = k[nm:, :nm]
        kr = kr - ksm.T @ sla.cho_solve(c, ksm, check_finite=False)
    return _standard_eigen(kr, mass, omega2_max)


def _standard_eigen(kr: np.ndarray, mass: np.ndarray, omega2_max: float):
    """Eigenpairs of K_r phi = omega^2 diag(mass) phi up to omega2_max, phi mass-normalized."""
    s = 1.0 / np.sqrt(mass)
    a = kr * s[:, None] * s[None, :]
    a = 0.5 * (a + a.T)
    w, y = sla.eigh(a, check_finite=False, driver="evd", overwrite_a=True)
    if w[0] < -1e-6 * max(1.0, abs(w[-1])):
        raise ModelEvaluationError("indefinite_matrix", f"negative eigenvalue {w[0]:.4g}")
    keep = w <= omega2_max
    return w[keep], y[:, keep] * s[:, None]


def solve_band(k: sp.csr_matrix, mass: np.ndarray, omega2_max: float):
    """Eigenpairs with omega^2 <= omega2_max; phi (n_master, m) mass-normalized.

    The first mass.size equations carry mass, the rest are massless and condensed:
    K_r = K_mm - K_ms K_ss^-1 K_sm, then (M^-1/2 K_r M^-1/2) y = omega^2 y, phi = M^-1/2 y.
    """
    nm = mass.size
    kr = k[:nm, :nm].toarray()
    if k.shape[0] > nm:
        ksm = k[nm:, :nm].tocsr()
        try:
            lu = spla.splu(k[nm:, nm:].tocsc())
        except RuntimeError as exc:  # SuperLU: "Factor is exactly singular"
            raise ModelEvaluationError("singular_matrix", f"massless block: {exc}") from exc
        cols = np.unique(ksm.indices)  # masters coupled to massless DOFs
        if cols.size:
            coupled = ksm[:, cols]
            kr[np.ix_(cols, cols)] -= np.asarray(coupled.T @ lu.solve(coupled.toarray()))
    return _standard_eigen(kr, mass, omega2_max)


def energy_shares_eq(phi: np.ndarray, op: _Operators) -> dict[str, np.ndarray]:
    """Kinetic-energy shares per group from equation-space modes (as :func:`.modes.energy_shares`)."""
    energies = {g: (phi[eqs] ** 2).T @ m for g, (eqs, m) in op.group_eqs.items()}
    total = sum(energies.values())
    out = {f"{g}_energy": e / total for g, e in energies.items()}
    deck_m = op.mass[op.deck_dir_eqs]  # (n_deck, 4), all deck DOFs carry mass
    deck_dir = np.einsum("nd,ndk->kd", deck_m, phi[op.deck_dir_eqs] ** 2)
    kind = np.argmax(deck_dir[:, [2, 1, 3, 0]], axis=1)
    out["mode_type"] = np.array(MODE_TYPES, dtype=object)[kind]
    return out
