"""Candidate effects generated from the user's OpenSees model itself (``candidates: auto``).

The model is built once at its initial parameter values and read from the OpenSees domain
(:func:`inspect_model`): nodes and coordinates, fixed DOFs, elements and their end nodes,
nodal masses, and each element's assembled stiffness block K_e (supports released, elements
removed one by one: K_e = K_before - K_after, exact for linear elements; stored by
(node, DOF) so that it applies to any build of the same mesh). From this topology
:func:`auto_effects` names the candidates; each has one parameter whose null value is
"no effect" and whose scale is the model's own:

- ``support_rotational_flexibility``: f = k_ref / k in [0, 5] (null 0); variants: each
  restrained node, ``all``; the fixed rotations are released and a spring k = k_ref / f
  added, k_ref = the members' K_e diagonal there (4 E I / L);
- ``support_translational_flexibility``: the same for the fixed horizontal translations
  (k_ref = 12 E I / L^3 of the columns there);
- ``semi_rigid_connections``: f = k_ref / k in [0, 5] (0); variants: each beam-to-column
  joint, ``level<i>``, ``all``; a rotational spring between each beam end and the joint
  (exact static condensation of the beam's own end rotations), k_ref = the beam's 4 E I / L;
- ``nodal_mass_change``: r in [-0.5, 1.5] (0); variants: each node with mass; m -> (1 + r) m;
- ``level_mass_change``: r in [-0.3, 0.5] (0); variants: ``level<i>``; m -> (1 + r) m at
  every node of one level (floor, deck);
- ``member_stiffness_change``: d in [-0.8, 1.5] (0); variants: each element,
  ``columns_storey<i>``, ``beams_level<i>``, ``columns``, ``beams``; K += d K_e (d < 0 a
  loss, d > 0 a gain);
- ``added_brace``: s = k / k_ref in [0, 5] (0); variants: node pairs one storey apart on
  neighbouring column lines; an axial spring k between the two nodes, k_ref = the median
  lateral stiffness 12 E I / L^3 of a column.

Levels are the distinct vertical coordinates (``vertical_axis``: y in 2D, z in 3D); a
column is an element within 25 deg of vertical, a beam one within 25 deg of horizontal; a
joint is an unrestrained node where a beam meets a column. Evaluation
(:class:`AutoModel`): the user's build, then the released supports, the extracted K and M
(:func:`framework.models.opensees_matrices.stiffness_and_mass`) plus the active effects'
terms, solved as :class:`~framework.models.opensees.OpenSeesModel` solves (scipy, mass-
normalized shapes). The effect terms are taken at the model's initial parameters (the
base parameters' errors change them only to second order). Linear elastic models only (no
gravity analysis); the stiffness blocks cost one extraction per element at catalogue
creation (once per process).

Hand-written effects combine with these: :func:`with_auto` adds the generated candidates
to a :class:`~framework.diagnosis.effects.Catalogue` whose factory returns an
``OpenSeesModel``; the hand-written effects are built by the factory, the generated ones
added to its matrices.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from framework.core.errors import InputError, ModelEvaluationError
from framework.core.parameters import Parameter, ParameterSet
from framework.diagnosis.effects import Catalogue, Effect
from framework.models.base import ModalResult, full_theta
from framework.models.opensees import OpenSeesModel, ops_module
from framework.models.opensees_matrices import DofMap, stiffness_and_mass

Key = tuple[int, int]  # (node tag, DOF 1-based)

#: element direction within this angle of vertical (horizontal) = column (beam)
AXIS_TOLERANCE_DEG = 25.0


@dataclass(frozen=True)
class Block:
    """A symmetric matrix term on the DOFs ``keys``."""

    keys: tuple[Key, ...]
    matrix: np.ndarray


@dataclass(frozen=True)
class Topology:
    """What :func:`inspect_model` read from the built domain."""

    ndm: int
    coords: Mapping[int, tuple[float, ...]]
    ndf: Mapping[int, int]
    fixed: Mapping[int, tuple[int, ...]]
    elements: Mapping[int, tuple[int, int]]
    blocks: Mapping[int, Block]
    masses: Mapping[int, float]
    vertical_axis: int
    levels: tuple[float, ...]

    def level_of(self, node: int) -> int:
        return int(np.argmin([abs(self.coords[node][self.vertical_axis] - z) for z in self.levels]))

    def kind(self, element: int) -> str:
        a, b = self.elements[element]
        d = np.subtract(self.coords[b], self.coords[a])
        length = float(np.linalg.norm(d))
        if length == 0:
            return "link"
        angle = math.degrees(math.acos(min(1.0, abs(d[self.vertical_axis]) / length)))
        if angle <= AXIS_TOLERANCE_DEG:
            return "column"
        return "beam" if angle >= 90 - AXIS_TOLERANCE_DEG else "brace"

    def storey(self, element: int) -> int:
        """1-based storey of a column: the level of its lower end + 1."""
        return min(self.level_of(n) for n in self.elements[element]) + 1

    def rotations(self, node: int) -> tuple[int, ...]:
        return (3,) if self.ndm == 2 and self.ndf[node] >= 3 else tuple(d for d in (4, 5, 6) if d <= self.ndf[node])

    def horizontal(self, node: int) -> tuple[int, ...]:
        return tuple(d for d in range(1, self.ndm + 1) if d - 1 != self.vertical_axis)

    def diagonal(self, key: Key) -> float:
        """Sum over elements of K_e at (key, key)."""
        total = 0.0
        for b in self.blocks.values():
            if key in b.keys:
                i = b.keys.index(key)
                total += b.matrix[i, i]
        return total


def _released(ops) -> dict[int, tuple[int, ...]]:
    """Remove every single-point constraint; {node: fixed DOFs} as they were."""
    fixed = {int(n): tuple(int(d) for d in ops.getFixedDOFs(n)) for n in ops.getFixedNodes()}
    for node, dofs in fixed.items():
        for dof in dofs:
            ops.remove("sp", node, dof)
    return fixed


def _stiffness(ops) -> np.ndarray:
    k, _ = stiffness_and_mass(ops)
    return k


def _keys(ops, nodes: Sequence[int]) -> dict[int, Key]:
    """{equation: (node, DOF)} of the current numbering."""
    out = {}
    for n in nodes:
        for d, eq in enumerate(ops.nodeDOFs(n), start=1):
            if eq >= 0:
                out[int(eq)] = (int(n), d)
    return out


def inspect_model(model: OpenSeesModel, vertical_axis: int | None = None, tol: float = 1e-9) -> Topology:
    """Build ``model`` at its initial values and read its topology and element stiffness blocks."""
    if model.gravity is not None:
        raise InputError(f"{model.name}: candidates: auto needs a linear model without a gravity analysis")
    ops = ops_module()
    values = dict(model.fixed) | full_theta(model.parameters, {})
    try:
        model._build_domain(ops, values)
        ndm = int(np.ravel(ops.getNDM())[0])
        nodes = [int(n) for n in ops.getNodeTags()]
        coords = {n: tuple(float(c) for c in ops.nodeCoord(n)) for n in nodes}
        masses = {}
        for n in nodes:
            m = ops.nodeMass(n)
            if m and max(m[:ndm]) > 0:
                masses[n] = float(max(m[:ndm]))
        fixed = _released(ops)
        elements = {int(e): tuple(int(n) for n in ops.eleNodes(e)) for e in ops.getEleTags()}
        k_prev = _stiffness(ops)
        ndf = {n: len(ops.nodeDOFs(n)) for n in nodes}
        keys = _keys(ops, nodes)
        blocks = {}
        for e in sorted(elements):
            ops.remove("element", e)
            k_next = _stiffness(ops)
            diff = k_prev - k_next
            k_prev = k_next
            scale = max(np.abs(diff).max(), 1e-300)
            idx = np.where(np.abs(diff).max(axis=1) > tol * scale)[0]
            blocks[e] = Block(tuple(keys[i] for i in idx), diff[np.ix_(idx, idx)])
    finally:
        ops.wipe()
    axis = vertical_axis if vertical_axis is not None else ndm - 1
    two = {e: n for e, n in elements.items() if len(n) == 2}
    levels = sorted({round(c[axis], 6) for c in coords.values()})
    return Topology(ndm, coords, ndf, fixed, two, {e: blocks[e] for e in two}, masses, axis, tuple(levels))


# ---- effects --------------------------------------------------------------------------------
@dataclass(frozen=True)
class AutoEffect:
    """A generated candidate: kind (an effect name of the table above), its parameter and variants."""

    name: str
    parameter: Parameter
    variants: dict[str, object] = field(default_factory=dict)  # variant -> what it acts on
    description: str = ""


def _column_lines(top: Topology) -> list[float]:
    """Horizontal positions (1st horizontal axis) of column ends, sorted."""
    h = [d - 1 for d in range(1, top.ndm + 1) if d - 1 != top.vertical_axis]
    xs = set()
    for e, (a, b) in top.elements.items():
        if top.kind(e) == "column":
            for n in (a, b):
                xs.add(tuple(round(top.coords[n][i], 6) for i in h))
    return sorted(xs)


def auto_effects(top: Topology) -> dict[str, AutoEffect]:
    """The generated candidates of a topology (see the module docstring)."""
    out: dict[str, AutoEffect] = {}
    supports = {n: d for n, d in top.fixed.items() if any(top.diagonal((n, x)) > 0 for x in d)}
    rot = {f"node{n}": (n,) for n, d in supports.items() if set(top.rotations(n)) & set(d)}
    if rot:
        rot["all"] = tuple(n for v in rot.values() for n in v)
        out["support_rotational_flexibility"] = AutoEffect(
            "support_rotational_flexibility",
            Parameter("support_rot_flex", 0.0, 0.0, 5.0, "-", "k_ref / k of the rotational support spring (0 = fixed)"),
            rot, "rotational spring where the model is fixed in rotation",
        )
    tra = {f"node{n}": (n,) for n, d in supports.items() if set(top.horizontal(n)) & set(d)}
    if tra:
        tra["all"] = tuple(n for v in tra.values() for n in v)
        out["support_translational_flexibility"] = AutoEffect(
            "support_translational_flexibility",
            Parameter("support_tra_flex", 0.0, 0.0, 5.0, "-", "k_ref / k of the horizontal support spring (0 = fixed)"),
            tra, "horizontal spring where the model is fixed in translation",
        )
    joints: dict[int, list[tuple[int, int]]] = {}
    for e, (a, b) in top.elements.items():
        if top.kind(e) != "beam":
            continue
        for n in (a, b):
            if n in top.fixed:
                continue
            has_column = any(top.kind(c) == "column" and n in top.elements[c] for c in top.elements)
            if has_column and top.rotations(n):
                joints.setdefault(n, []).append((e, n))
    if joints:
        var: dict[str, object] = {f"node{n}": tuple(ends) for n, ends in sorted(joints.items())}
        by_level: dict[int, list] = {}
        for n, ends in joints.items():
            by_level.setdefault(top.level_of(n), []).extend(ends)
        var |= {f"level{lv}": tuple(ends) for lv, ends in sorted(by_level.items())}
        var["all"] = tuple(x for ends in joints.values() for x in ends)
        out["semi_rigid_connections"] = AutoEffect(
            "semi_rigid_connections",
            Parameter("connection_flex", 0.0, 0.0, 5.0, "-", "k_ref / k of the beam-end springs (0 = rigid)"),
            var, "rotational flexibility between beam ends and columns",
        )
    if top.masses:
        out["nodal_mass_change"] = AutoEffect(
            "nodal_mass_change",
            Parameter("nodal_mass_ratio", 0.0, -0.5, 1.5, "-", "added (> 0) or missing (< 0) mass / the node's mass"),
            {f"node{n}": (n,) for n in sorted(top.masses)}, "added or missing mass at one node",
        )
        levels: dict[int, list[int]] = {}
        for n in top.masses:
            levels.setdefault(top.level_of(n), []).append(n)
        out["level_mass_change"] = AutoEffect(
            "level_mass_change",
            Parameter("level_mass_ratio", 0.0, -0.3, 0.5, "-", "added (> 0) or missing (< 0) mass / the level's mass"),
            {f"level{lv}": tuple(sorted(ns)) for lv, ns in sorted(levels.items())},
            "added or missing mass over one level (floor, deck)",
        )
    members: dict[str, object] = {f"ele{e}": (e,) for e in sorted(top.elements)}
    groups: dict[str, list[int]] = {}
    for e in sorted(top.elements):
        kind = top.kind(e)
        if kind == "column":
            groups.setdefault(f"columns_storey{top.storey(e)}", []).append(e)
            groups.setdefault("columns", []).append(e)
        elif kind == "beam":
            groups.setdefault(f"beams_level{top.level_of(top.elements[e][0])}", []).append(e)
            groups.setdefault("beams", []).append(e)
    members |= {k: tuple(v) for k, v in groups.items() if len(v) > 1}
    out["member_stiffness_change"] = AutoEffect(
        "member_stiffness_change",
        Parameter("stiffness_change", 0.0, -0.8, 1.5, "-", "K_e -> (1 + d) K_e (d < 0 loss, d > 0 gain)"),
        members, "stiffness loss or gain of a member or a group of members",
    )
    lines = _column_lines(top)
    col_nodes = {n for e, ns in top.elements.items() if top.kind(e) == "column" for n in ns}
    h = [d - 1 for d in range(1, top.ndm + 1) if d - 1 != top.vertical_axis]
    pos = {n: tuple(round(top.coords[n][i], 6) for i in h) for n in col_nodes}
    pairs = {}
    for a in sorted(col_nodes):
        for b in sorted(col_nodes):
            la, lb = top.level_of(a), top.level_of(b)
            if lb != la + 1 or pos[a] not in lines or pos[b] not in lines:
                continue
            ia, ib = lines.index(pos[a]), lines.index(pos[b])
            connected = any(set(ns) == {a, b} for ns in top.elements.values())
            if abs(ia - ib) == 1 and not connected:
                pairs[f"n{a}-n{b}"] = (a, b)
    if pairs:
        out["added_brace"] = AutoEffect(
            "added_brace",
            Parameter("brace_stiffness_ratio", 0.0, 0.0, 5.0, "-", "axial stiffness of the added element / k_ref"),
            pairs, "an added stiffening element (brace, infill strut, partition) between two nodes",
        )
    return out


# ---- matrix terms ---------------------------------------------------------------------------
def _brace_block(top: Topology, a: int, b: int, k: float) -> Block:
    d = np.subtract(top.coords[b], top.coords[a])
    e = d / np.linalg.norm(d)
    ee = np.outer(e, e) * k
    keys = tuple((a, i + 1) for i in range(top.ndm)) + tuple((b, i + 1) for i in range(top.ndm))
    return Block(keys, np.block([[ee, -ee], [-ee, ee]]))


def _condensed_end(block: Block, node: int, rotations: Sequence[int], flex: float) -> Block:
    """dK of a rotational spring k = k_ref / flex between a member's end rotations and its node.

    The member's end rotations become internal DOFs (the member's couplings move to them),
    the spring joins them to the node's rotations, and the internal DOFs are condensed:
    K_c = A_oo - A_oi A_ii^-1 A_io; the term returned is K_c - K_e.
    """
    ke = block.matrix
    m = len(block.keys)
    r_idx = [block.keys.index((node, d)) for d in rotations if (node, d) in block.keys]
    p = len(r_idx)
    if p == 0 or flex <= 0:
        return Block(block.keys, np.zeros_like(ke))
    k_ref = float(np.mean([ke[i, i] for i in r_idx]))
    k = k_ref / flex
    a = np.zeros((m + p, m + p))
    a[:m, :m] = ke
    a[r_idx, :] = 0.0
    a[:, r_idx] = 0.0
    for j, rj in enumerate(r_idx):
        a[:m, m + j] = ke[:, rj]
        a[m + j, :m] = ke[rj, :]
        for i, ri in enumerate(r_idx):
            a[m + i, m + j] = ke[ri, rj]
    for j in range(p):  # the internal rows' couplings to the node's own rotations are the member's
        for ri in r_idx:
            a[ri, m + j] = 0.0
            a[m + j, ri] = 0.0
    for j, rj in enumerate(r_idx):
        a[rj, rj] += k
        a[m + j, m + j] += k
        a[rj, m + j] -= k
        a[m + j, rj] -= k
    cond = a[:m, :m] - a[:m, m:] @ np.linalg.solve(a[m:, m:], a[m:, :m])
    return Block(block.keys, cond - ke)


@dataclass(frozen=True)
class AutoModel:
    """The user's OpenSees model with generated effects ``active`` {effect: variant}."""

    base: OpenSeesModel
    topology: Topology
    effects: Mapping[str, AutoEffect]
    active: Mapping[str, str]
    name: str = "auto"

    @property
    def parameters(self) -> ParameterSet:
        return ParameterSet(list(self.base.parameters) + [self.effects[e].parameter for e in self.active])

    @property
    def dofs(self) -> tuple[str, ...]:
        return self.base.dofs

    def modal(self, theta: Mapping[str, float]) -> ModalResult:
        values = full_theta(self.parameters, theta)
        base_values = dict(self.base.fixed) | {p.name: values[p.name] for p in self.base.parameters}
        top = self.topology
        terms: list[Block] = []
        mass_terms: dict[int, float] = {}
        release: list[Key] = []
        springs: dict[Key, float] = {}
        for name, variant in self.active.items():
            eff = self.effects[name]
            v = float(values[eff.parameter.name])
            target = eff.variants[variant]
            if name.startswith("support_") and v > 0:
                for node in target:
                    dofs = top.rotations(node) if "rotational" in name else top.horizontal(node)
                    for d in dofs:
                        if d in top.fixed.get(node, ()):
                            key = (node, d)
                            k_ref = top.diagonal(key)
                            if k_ref > 0:
                                release.append(key)
                                springs[key] = k_ref / v
            elif name == "semi_rigid_connections":
                for element, node in target:
                    terms.append(_condensed_end(top.blocks[element], node, top.rotations(node), v))
            elif name in ("nodal_mass_change", "level_mass_change"):
                for node in target:
                    mass_terms[node] = mass_terms.get(node, 0.0) + v * top.masses[node]
            elif name == "member_stiffness_change" and v != 0:
                terms.extend(Block(top.blocks[e].keys, v * top.blocks[e].matrix) for e in target)
            elif name == "added_brace" and v > 0:
                terms.append(_brace_block(top, *target, v * self.k_brace_ref))
        stiffness, mass, rows, eq = _assembled(self.base, base_values, tuple(release))
        for block in terms:
            idx = np.array([eq.get(k, -1) for k in block.keys])
            ok = np.where(idx >= 0)[0]
            stiffness[np.ix_(idx[ok], idx[ok])] += block.matrix[np.ix_(ok, ok)]
        for key, k in springs.items():
            if eq.get(key, -1) >= 0:
                stiffness[eq[key], eq[key]] += k
        for node, dm in mass_terms.items():
            for d in range(1, top.ndm + 1):
                i = eq.get((node, d), -1)
                if i >= 0:
                    mass[i, i] += dm
        omega2, shapes, _ = self.base._solve(stiffness, mass, rows)
        return self.base._result(omega2, shapes)

    @property
    def k_brace_ref(self) -> float:
        return brace_reference(self.topology)


def brace_reference(top: Topology) -> float:
    """Median lateral stiffness of a column (its K_e at the top node's first horizontal DOF)."""
    vals = []
    for e, (a, b) in top.elements.items():
        if top.kind(e) == "column":
            upper = a if top.level_of(a) > top.level_of(b) else b
            key = (upper, top.horizontal(upper)[0])
            blk = top.blocks[e]
            if key in blk.keys:
                vals.append(blk.matrix[blk.keys.index(key), blk.keys.index(key)])
    return float(np.median(vals)) if vals else 1.0


#: (id of the base model, base values, released DOFs) -> (K, M, rows, equations); a few
#: entries: screening and finite differences evaluate many effect values at the same base point
_ASSEMBLED: OrderedDict = OrderedDict()
_ASSEMBLED_SIZE = 4


def _assembled(base: OpenSeesModel, values: dict, release: tuple[Key, ...]):
    """The user's model built at ``values`` with ``release`` supports freed: (K, M, rows, {key: equation})."""
    key = (id(base), tuple(sorted((k, float(v)) for k, v in values.items() if isinstance(v, int | float))), release)
    hit = _ASSEMBLED.get(key)
    if hit is not None:
        _ASSEMBLED.move_to_end(key)
        k, m, rows, eq = hit
        return k.copy(), m.copy(), rows, eq
    ops = ops_module()
    try:
        _, constraints = base._build_domain(ops, values)
        for node, dof in release:
            ops.remove("sp", node, dof)
        stiffness, mass = stiffness_and_mass(ops)
        dof_map = DofMap(ops, constraints)
        rows = [dof_map.row(node, direction) for node, direction in base.measured_dofs.values()]
        eq = {}
        for node in ops.getNodeTags():
            for d, e in enumerate(ops.nodeDOFs(node), start=1):
                eq[(int(node), d)] = int(e)
    finally:
        ops.wipe()
    if any(r is None for r in rows):
        raise ModelEvaluationError("unmapped_constraint", "a measured DOF lies on an unrecorded constraint node")
    _ASSEMBLED[key] = (stiffness, mass, rows, eq)
    while len(_ASSEMBLED) > _ASSEMBLED_SIZE:
        _ASSEMBLED.popitem(last=False)
    return stiffness.copy(), mass.copy(), rows, eq


# ---- catalogues -----------------------------------------------------------------------------
def as_effect(a: AutoEffect, hidden: Mapping[str, tuple] | None = None) -> Effect:
    """The catalogue Effect of a generated candidate (hidden: (variants, value range) for generated data)."""
    hv, rng = (hidden or {}).get(a.name, (None, None))
    return Effect(
        a.name,
        a.description + " (generated from the model)",
        (a.parameter,),
        tuple(a.variants),
        hidden_values={a.parameter.name: tuple(rng)} if rng else {},
        hidden_variants=tuple(hv) if hv else None,
    )


def with_auto(catalogue: Catalogue, hidden: Mapping[str, tuple] | None = None,
              vertical_axis: int | None = None) -> Catalogue:  # fmt: skip
    """``catalogue`` plus the candidates generated from its model under test (hand-written effects kept).

    hidden: {auto effect: (hidden variants or None, (low, high))} for generated data.
    """
    base = catalogue.model({})
    if not isinstance(base, OpenSeesModel):
        raise InputError(f"{catalogue.structure}: candidates: auto needs an OpenSees model (OpenSeesModel), "
                         f"the factory returned {type(base).__name__}")  # fmt: skip
    try:
        top = inspect_model(base, vertical_axis)
    except ModelEvaluationError as exc:  # the user's build raised: one line naming it
        raise InputError(f"structure {catalogue.structure!r}: building the model failed: {exc}") from None
    generated = auto_effects(top)
    clash = sorted(set(generated) & set(catalogue.effects))
    if clash:
        raise InputError(f"{catalogue.structure}: hand-written effects {clash} clash with generated names")
    hand = catalogue.effects
    factory = catalogue.factory

    def auto_factory(active, **options):
        hand_active = {k: v for k, v in active.items() if k in hand}
        auto_active = {k: v for k, v in active.items() if k not in hand}
        model = factory(hand_active, **options)
        if not auto_active:
            return model
        return AutoModel(model, top, generated, auto_active, name=f"{model.name}+auto")

    effects = dict(hand) | {k: as_effect(a, hidden) for k, a in generated.items()}
    settings = {"screen_keep": 3, "screen_points": 4} | dict(catalogue.settings)
    description = (catalogue.description + "; candidates generated from the model").strip("; ")
    return replace(catalogue, effects=effects, factory=auto_factory, settings=settings, generated=tuple(generated),
                   description=description)  # fmt: skip


def with_candidates(catalogue: Catalogue, candidates: str | list[str] | None) -> Catalogue:
    """The catalogue whose diagnosis tries ``candidates``: "catalogue" (default: the hand-written
    effects), "auto" (the effects generated from the model), or a list of effect names, where
    "auto" stands for every generated effect (hand-written and generated combined)."""
    if candidates is None or candidates == "catalogue":
        hand = tuple(k for k in catalogue.effects if k not in catalogue.generated)
        return replace(catalogue, candidates=hand)
    names = [candidates] if isinstance(candidates, str) else list(candidates)
    if "auto" in names and not catalogue.generated:
        catalogue = with_auto(catalogue)
    chosen: list[str] = []
    for n in names:
        chosen.extend(catalogue.generated if n == "auto" else [n])
    unknown = sorted(set(chosen) - set(catalogue.effects))
    if unknown:
        raise InputError(f"{catalogue.structure}: candidates {unknown} unknown; known: "
                         f"{sorted(catalogue.effects)} or 'auto'")  # fmt: skip
    return replace(catalogue, candidates=tuple(dict.fromkeys(chosen)))


__all__ = ["AutoEffect", "AutoModel", "Topology", "auto_effects", "inspect_model", "with_candidates",
           "with_auto"]  # fmt: skip
