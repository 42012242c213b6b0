"""Assembled stiffness and mass matrices of the OpenSees domain, and node DOFs in equation space.

Extraction: OpenSees prints the matrix A of a ``FullGeneral`` system of equations
(``printA``). With the ``GimmeMCK`` integrator (factors m, c, k) the assembled matrix is
A = m M + c C + k K_t, so :func:`stiffness_and_mass` reads the tangent stiffness K_t at the
committed state (what OpenSees' own eigen analysis uses, e.g. after a gravity analysis) and
the mass M without an analysis step and without changing the state. Equations: Plain
numberer, Transformation constraints, i.e. one equation per DOF that is neither fixed nor
constrained by a multi-point constraint, numbered node by node (``ops.nodeDOFs``).
:func:`static_stiffness` is the variant with one linear static step (the bridge's fast path).

Node DOFs from equations (:class:`DofMap`): u = r . q with q the equation-space vector and
r a sparse row per node DOF: a free DOF is one equation; a fixed DOF is zero; a DOF of a
node constrained by a multi-point constraint is u_c = C u_r, from the retained node's
equations. C is known for the constraints the build created through ``ops.equalDOF``
(C = I on the listed DOFs), ``ops.rigidLink('bar', ...)`` (equal translations),
``ops.rigidLink('beam', ...)`` (u_c = u_r + theta_r x d, theta_c = theta_r, d = x_c - x_r in
initial coordinates) and ``ops.rigidDiaphragm`` (in-plane rigid-body motion about the
perpendicular axis): :func:`recording_constraints` records those commands while the build
runs. Other multi-point constraints (``equalDOF_Mixed``, ``equationConstraint``, commands
imported by name so that the record misses them) leave their constrained nodes unmapped
(:meth:`DofMap.row` returns None).

Why hand-written: OpenSeesPy 3.8 exports neither the constraint matrices nor a sparse
tangent; ``printA`` of a dense system is the only exact export (memory and time O(n^2) per
matrix, documented in :mod:`framework.models.opensees`).
"""

from __future__ import annotations

import array
import contextlib
import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from framework.core.errors import ModelEvaluationError

#: Constraint commands recorded during a build (see :func:`recording_constraints`).
RECORDED_COMMANDS = ("equalDOF", "rigidLink", "rigidDiaphragm")


def printed_matrix(ops) -> np.ndarray:
    """A of the current FullGeneral system (``printA('-ret')``) as an (n, n) array."""
    values = ops.printA("-ret")
    if isinstance(values, float | int):
        values = [values]
    a = np.frombuffer(array.array("d", values), dtype=float)
    n = math.isqrt(a.size)
    if n * n != a.size:  # pragma: no cover - OpenSees always prints a square matrix
        raise ModelEvaluationError("extraction_failed", f"printA returned {a.size} values, not a square matrix")
    return a.reshape(n, n)


def _extraction_system(ops) -> None:
    ops.system("FullGeneral")
    ops.numberer("Plain")
    ops.constraints("Transformation")
    ops.algorithm("Linear")


def stiffness_and_mass(ops) -> tuple[np.ndarray, np.ndarray]:
    """(K_t, M) of the current domain in equation space, dense (n, n); state unchanged.

    Replaces any analysis defined before (e.g. the gravity analysis, whose converged state
    is kept by ``loadConst``) with a transient GimmeMCK one: printA forms A = K_t (factors
    0, 0, 1), then A = M (1, 0, 0); ``initialize`` numbers the equations without a solve.
    """
    ops.wipeAnalysis()
    _extraction_system(ops)
    ops.integrator("GimmeMCK", 0.0, 0.0, 1.0)
    ops.analysis("Transient")
    ops.initialize()
    stiffness = printed_matrix(ops)
    ops.integrator("GimmeMCK", 1.0, 0.0, 0.0)
    mass = printed_matrix(ops)
    return stiffness, mass


def static_stiffness(ops) -> np.ndarray:
    """K_t after one linear static step with zero load increment (FullGeneral, Plain, Transformation).

    The step solves for the out-of-balance load of the current state (e.g. prestressed
    elements of a freshly built model) before printA forms the tangent at the new state.
    """
    _extraction_system(ops)
    ops.integrator("LoadControl", 0.0)
    ops.analysis("Static")
    if ops.analyze(1) != 0:
        raise ModelEvaluationError("singular_matrix", "extraction step of the stiffness failed")
    return printed_matrix(ops)


@contextlib.contextmanager
def recording_constraints(ops) -> Iterator[list[tuple[str, tuple]]]:
    """Within the block, calls of ``ops.equalDOF``, ``ops.rigidLink`` and ``ops.rigidDiaphragm``
    are appended as (command, arguments) to the yielded list (and executed as usual)."""
    record: list[tuple[str, tuple]] = []
    originals = {name: getattr(ops, name) for name in RECORDED_COMMANDS if hasattr(ops, name)}

    def recorder(name, command):
        def recorded(*args):
            out = command(*args)
            record.append((name, args))
            return out

        recorded.__name__ = recorded.__qualname__ = name
        return recorded

    for name, command in originals.items():
        setattr(ops, name, recorder(name, command))
    try:
        yield record
    finally:
        for name, command in originals.items():
            setattr(ops, name, command)


#: {constrained DOF: [(retained DOF, coefficient)]}, DOFs 0-based
Coupling = dict[int, list[tuple[int, float]]]


def _coupling(kind: str, ndm: int, ndf: int, d: np.ndarray, perpendicular: int = 0) -> Coupling | None:
    """Rigid-body terms of C beyond the identity pairing: {constrained DOF: [(retained DOF, coefficient)]}.

    ``d`` = x_c - x_r (initial coordinates); DOFs 0-based. u_c = u_r + theta_r x d. None: C unknown.
    """
    if kind in ("equalDOF", "bar"):
        return {}
    if kind == "beam":
        if ndm == 3 and ndf == 6:
            # theta x d = (ty dz - tz dy, tz dx - tx dz, tx dy - ty dx)
            return {
                0: [(4, d[2]), (5, -d[1])],
                1: [(5, d[0]), (3, -d[2])],
                2: [(3, d[1]), (4, -d[0])],
            }
        if ndm == 2 and ndf == 3:
            return {0: [(2, -d[1])], 1: [(2, d[0])]}
        return None
    if kind == "diaphragm" and ndm == 3 and ndf == 6 and perpendicular in (1, 2, 3):
        axis = perpendicular - 1  # rotation DOF 3 + axis about the perpendicular
        e = np.zeros(3)
        e[axis] = 1.0
        arm = np.cross(e, d)  # translation per unit rotation about the axis
        return {i: [(3 + axis, float(arm[i]))] for i in range(3) if i != axis and arm[i] != 0.0}
    return None


def _parse_record(record: list[tuple[str, tuple]]) -> dict[int, tuple[int, str, int]]:
    """{constrained node: (retained node, kind, perpendicular axis)} from recorded commands."""
    out: dict[int, tuple[int, str, int]] = {}
    for name, args in record:
        try:
            if name == "equalDOF":
                out[int(args[1])] = (int(args[0]), "equalDOF", 0)
            elif name == "rigidLink":
                out[int(args[2])] = (int(args[1]), str(args[0]), 0)
            elif name == "rigidDiaphragm":
                for node in args[2:]:
                    out[int(node)] = (int(args[1]), "diaphragm", int(args[0]))
        except (IndexError, TypeError, ValueError):  # pragma: no cover - OpenSees rejected the call already
            continue
    return out


@dataclass(frozen=True)
class DofRow:
    """u = coefficients . q[equations] for one node DOF (empty: a fixed DOF, u = 0)."""

    equations: np.ndarray
    coefficients: np.ndarray

    def of(self, q: np.ndarray) -> np.ndarray:
        """Value(s) of the DOF for equation-space vector(s) q (n,) or (n, k)."""
        if self.equations.size == 0:
            return np.zeros(q.shape[1:]) if q.ndim > 1 else np.float64(0.0)
        return self.coefficients @ q[self.equations]


class DofMap:
    """Rows u = r . q of node DOFs in the equation numbering of the current analysis.

    record: the (command, arguments) list of :func:`recording_constraints`. Rows are
    computed per node on first use; :meth:`row` returns None for a DOF of a node whose
    multi-point constraint is not known (see the module docstring).
    """

    def __init__(self, ops, record: list[tuple[str, tuple]]):
        self._ops = ops
        self._ndm = int(np.ravel(ops.getNDM())[0])
        self._constrained = set(int(n) for n in ops.getConstrainedNodes())
        self._nodes = set(int(n) for n in ops.getNodeTags())
        self._known = _parse_record(record)
        self._rows: dict[int, list[DofRow] | None] = {}

    def row(self, node: int, dof: int) -> DofRow | None:
        """Row of DOF ``dof`` (1-based, OpenSees' numbering) of ``node``; None if unmapped."""
        rows = self.node_rows(node)
        if rows is not None and not 1 <= dof <= len(rows):
            raise ModelEvaluationError("bad_dof", f"node {node} has DOFs 1..{len(rows)}, not {dof}")
        return None if rows is None else rows[dof - 1]

    def node_rows(self, node: int) -> list[DofRow] | None:
        node = int(node)
        if node not in self._rows:
            if node not in self._nodes:
                raise ModelEvaluationError("bad_dof", f"the model has no node {node}")
            self._rows[node] = self._compute(node)
        return self._rows[node]

    def _free_rows(self, node: int) -> list[DofRow]:
        return [_single(eq) for eq in self._ops.nodeDOFs(node)]

    def _compute(self, node: int) -> list[DofRow] | None:
        ops = self._ops
        if node not in self._constrained:
            return self._free_rows(node)
        known = self._known.get(node)
        if known is None:
            return None
        retained, kind, perpendicular = known
        if retained in self._constrained or retained not in ops.getRetainedNodes(node):
            return None
        c_dofs = [int(d) - 1 for d in ops.getConstrainedDOFs(node, retained)]
        r_dofs = [int(d) - 1 for d in ops.getRetainedDOFs(retained, node)]
        ndf = len(ops.nodeDOFs(node))
        d = np.zeros(3)
        offset = np.subtract(ops.nodeCoord(node), ops.nodeCoord(retained))
        d[: offset.size] = offset
        coupling = _coupling(kind, self._ndm, ndf, d, perpendicular)
        if coupling is None or len(c_dofs) != len(r_dofs):
            return None
        own = [dof for dof in range(ndf) if dof not in c_dofs]
        own_eqs = ops.nodeDOFs(node)[: len(own)]
        r_eqs = ops.nodeDOFs(retained)
        rows: list[DofRow] = [_single(-1)] * ndf
        for dof, eq in zip(own, own_eqs):
            rows[dof] = _single(eq)
        for c_dof, r_dof in zip(c_dofs, r_dofs):
            terms = [(r_dof, 1.0)] + list(coupling.get(c_dof, []))
            eqs = [r_eqs[j] for j, _ in terms]
            keep = [i for i, eq in enumerate(eqs) if eq >= 0]  # fixed retained DOFs contribute nothing
            rows[c_dof] = DofRow(np.array([eqs[i] for i in keep], dtype=int),
                                 np.array([terms[i][1] for i in keep], dtype=float))
        return rows


def _single(eq: int) -> DofRow:
    if eq < 0:
        return DofRow(np.zeros(0, dtype=int), np.zeros(0))
    return DofRow(np.array([int(eq)]), np.ones(1))
