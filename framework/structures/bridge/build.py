"""OpenSeesPy build of the bridge (:func:`build_bridge`), its gravity analysis and cable tensions.

Model (run through :class:`~framework.models.opensees.OpenSeesModel`, see
:mod:`framework.structures.bridge.model`):

- deck: 48 ``elasticBeamColumn`` elements (Linear transformation) on the spine, fully
  composite section transformed to steel (E = 200 GPa, G = 77 GPa): I = 0.00439 m^4
  (vertical bending, local y), 0.06140 m^4 (lateral bending, local z), J = 0.00810 m^4
  (given); area from the section reading (:mod:`.section`, 0.125 m^2);
  cable anchors and sensor points on both edges are ``rigidLink('beam')`` slaves of the
  spine nodes;
- pylon: 40 ``elasticBeamColumn`` elements: two inclined 400WC328 legs of 18 elements each
  (strong axis bending in the plane of the A-frame; fixed bases at z = -4.0 m, 2.4 m off
  the axis, meeting at the apex z = +18.4 m; total height 22.4 m), a crossbeam at deck
  level carrying the pivot bearings (400WC328) and a strut at z = 9.2 m (200x200x10 SHS),
  2 elements each; Linear transformations (no P-delta);
- cables: anchored 7.4 m (Cab-3), 16.1 m (Cab-2) and 23.6 m (Cab-1) each side of the
  pylon at y = +-1.175 m (edge pipes); each a chain of ``cable_elements`` (1, 2, 4, 8)
  ``corotTruss`` elements (E = 165 GPa, A = 804 mm^2, 6.31 kg/m lumped at the chain
  nodes, interior node rotations fixed) with the pretension as initial strain
  (``InitStrainMaterial`` around ``Elastic``, eps0 = T / (E A));
- bearings: ``zeroLength`` springs between the spine and ground (abutments) or the
  crossbeam (pylon): longitudinal = shear stiffness, vertical, torsional (SPEC values, per
  support line), lateral = see ``lateral_restraint``; rotations about y and z are free;
- masses: from the section (:func:`.section.deck_mass_per_m`: 1618 kg/m and 1036 kg m^2/m
  about the spine for the default reading), lumped at the spine nodes; pylon 328 kg/m; no
  mass on constrained (rigid-link) nodes; rotational inertia only about the deck axis (the
  mass centroid lies 0.08 m above the spine: the lateral-torsional mass coupling,
  (S^2 / (m I_x)) = 0.010, is neglected);
- gravity: nodal loads m g, one-step Newton (UmfPack) on the corotational model
  (:data:`GRAVITY`); the eigen solution follows on the deformed, stressed state (plain
  path: OpenSees default solver, ~100 modes; fast path: :mod:`.fast`), and the modes are
  classified by kinetic-energy share (:mod:`.modes`).

Options of :func:`build_bridge` (validated by :func:`check_options`):

- ``cable_elements`` (1, 2, 4, 8; default 4): elements per cable. One element loses the
  2nd vertical mode (deck-cable coupled, cables swinging laterally).
- ``lateral_restraint`` ("rigid" default | "guided" | "shear"): lateral stiffness of the
  bearings (:func:`lateral_stiffness`). The pivot bearings at the pylon hold the deck in
  plan and the sliding bearings at the abutments are guided: the lateral restraint is
  steel on steel, so "rigid" (RIGID_FACTOR x the vertical stiffness, not scaled by
  K_bearing). "guided" (k_y = vertical stiffness x K_bearing: guides as stiff as the
  elastomer in compression) was the default before issue 15; with "shear" (the
  elastomer's shear stiffness) the deck sways as a rigid body at about 1.3 Hz, far below
  any measured lateral mode.
- ``deck_section`` ("steel_overhangs" default | "slab_overhangs"): the reading of the deck
  section that gives the deck's area, mass and mass moment of inertia (:mod:`.section`);
  "slab_overhangs" is the estimate before issue 15.
- ``tensions`` ("installed" default | "final"): "installed" applies 55/95/75 kN as the
  initial strain before gravity (the deck weight then raises them); "final" iterates the
  initial strain (outer gravity runs, at most ``final_iterations``) until the dead-load tensions
  equal 55/95/75 kN. See docs/bridge.md for the comparison.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from framework.core.errors import InputError
from framework.models.opensees import GravityAnalysis, ops_module, run_static
from framework.structures.bridge.geometry import (
    ANCHOR_NODE0,
    ANCHOR_OFFSETS,
    ANCHOR_Y_M,
    BEARINGS,
    CABLE_AREA_M2,
    CABLE_MASS_KG_PER_M,
    CABLE_NODE0,
    CROSSBEAM,
    DECK_I_LATERAL_M4,
    DECK_I_VERTICAL_M4,
    DECK_J_M4,
    DECK_LENGTH_M,
    DESIGN_TENSION_N,
    E_CABLE_PA,
    GROUND_NODE0,
    LEG,
    N_DECK_ELEMENTS,
    N_LEG_ABOVE_DECK,
    N_LEG_BELOW_DECK,
    PYLON_BASE_HALF_WIDTH_M,
    PYLON_BASE_Z_M,
    PYLON_NODE0,
    PYLON_TOP_Z_M,
    PYLON_X_M,
    STRUT,
    STRUT_LEVEL,
    BridgeInfo,
    deck_node,
    sensor_dofs,
    sensor_offsets,
    sensor_points,
)
from framework.structures.bridge.section import E_STEEL_PA, G_STEEL_PA, SECTIONS, deck_area_m2, deck_mass_per_m

GRAVITY_M_PER_S2 = 9.81


LATERAL_RESTRAINTS = ("rigid", "guided", "shear")
#: lateral stiffness of a "rigid" restraint: this factor times the support line's vertical
#: stiffness (1.6e11 N/m at the abutments, 7.7e10 N/m at the pylon): ten times stiffer
#: changes no frequency by more than 2e-4 relative
RIGID_FACTOR = 1000.0


def check_options(cable_elements: int, lateral_restraint: str, tensions: str, deck_section: str = SECTIONS[0]) -> None:
    """Raise :class:`InputError` naming the option for a value outside its allowed set."""
    if cable_elements not in (1, 2, 4, 8):
        raise InputError(f"bridge option cable_elements must be 1, 2, 4 or 8, got {cable_elements!r}")
    if lateral_restraint not in LATERAL_RESTRAINTS:
        raise InputError(f"bridge option lateral_restraint must be one of {list(LATERAL_RESTRAINTS)}, "
                         f"got {lateral_restraint!r}")
    if tensions not in ("installed", "final"):
        raise InputError(f"bridge option tensions must be 'installed' or 'final', got {tensions!r}")
    if deck_section not in SECTIONS:
        raise InputError(f"bridge option deck_section must be one of {list(SECTIONS)}, got {deck_section!r}")


def lateral_stiffness(bearing: Mapping[str, float], restraint: str, k_bearing: float) -> float:
    """Lateral spring (N/m) of a support line: "rigid" (RIGID_FACTOR x vertical, not scaled by
    K_bearing: a steel guide, not the elastomer), "guided" (the vertical stiffness, scaled by
    K_bearing) or "shear" (the elastomer's shear stiffness, scaled by K_bearing)."""
    if restraint == "rigid":
        return RIGID_FACTOR * bearing["vertical"]
    return k_bearing * (bearing["vertical"] if restraint == "guided" else bearing["shear"])


def _cable_group_strains(ea_n: float, tensions: Mapping[str, float]) -> dict[str, float]:
    """Initial strain eps0 = T / (E A) per cable group."""
    return {g: tensions[g] / ea_n for g in DESIGN_TENSION_N}


def _target_tensions(values: Mapping[str, float]) -> dict[str, float]:
    out = dict(DESIGN_TENSION_N)
    out["Cab-1"] = DESIGN_TENSION_N["Cab-1"] * float(values["T_Cab1"])
    return out


def build_bridge(
    values: Mapping[str, float],
    *,
    cable_elements: int = 4,
    lateral_restraint: str = "rigid",
    tensions: str = "installed",
    deck_section: str = SECTIONS[0],
    final_iterations: int = 20,
    initial_strain: Mapping[str, float] | None = None,
) -> BridgeInfo:
    """Create the bridge in the OpenSees domain for parameter ratios ``values``.

    With ``tensions="final"`` the initial strain of each cable group is corrected by
    eps0 <- eps0 + (T_target - T) / (E A) in gravity runs (each rebuilding the domain)
    until every group's tension T is within ``FINAL_TOLERANCE`` of its target or after
    ``final_iterations`` runs, then built once more; the mean axial force over a group's
    elements is its tension T. The structure relaxes about three quarters of each correction,
    so the error falls by only about a quarter per run.
    """
    check_options(cable_elements, lateral_restraint, tensions, deck_section)
    options = {"cable_elements": cable_elements, "lateral_restraint": lateral_restraint, "deck_section": deck_section}
    ops = ops_module()
    ea_n = E_CABLE_PA * float(values["K_cable"]) * CABLE_AREA_M2
    target = _target_tensions(values)
    eps = dict(initial_strain) if initial_strain else _cable_group_strains(ea_n, target)
    if tensions == "final" and initial_strain is None:
        for _ in range(final_iterations):
            ops.wipe()
            info = _build(ops, values, options, eps, target)
            run_static(ops, GRAVITY)
            force = cable_tensions(ops, info)
            if max(abs(force[g] / target[g] - 1.0) for g in eps) <= FINAL_TOLERANCE:
                break
            eps = {g: eps[g] + (target[g] - force[g]) / ea_n for g in eps}
        ops.wipe()
    return _build(ops, values, options, eps, target)


#: relative tolerance of the dead-load tensions with ``tensions="final"``
FINAL_TOLERANCE = 0.005

#: the gravity analysis used by every bridge evaluation (one Newton step, UmfPack)
GRAVITY = GravityAnalysis(steps=1, tolerance=1e-9, max_iterations=30, system="UmfPack", numberer="RCM")


def cable_tensions(ops, info: BridgeInfo) -> dict[str, float]:
    """Mean axial force (N) over the elements of each cable group in the current state."""
    forces = [ops.eleResponse(e, "axialForce")[0] for c in info.cable_elements.values() for x in c for e in x]
    return cable_tensions_from(np.array(forces), info)


def cable_tensions_from(forces: np.ndarray, info: BridgeInfo) -> dict[str, float]:
    """Group means of element axial forces given in the order of ``info.cable_elements``."""
    out, start = {}, 0
    for group, cables in info.cable_elements.items():
        n = sum(len(c) for c in cables)
        out[group] = float(np.mean(forces[start : start + n]))
        start += n
    return out


def _build(ops, values, options, eps, target) -> BridgeInfo:
    cable_elements = options["cable_elements"]
    ky = float(values["K_y_deck"])
    kx = float(values["K_x_deck"])
    kt = float(values["K_t_deck"])
    kb = float(values["K_bearing"])
    kc = float(values["K_cable"])
    m_deck, ix_deck = deck_mass_per_m(options["deck_section"])
    deck_area = deck_area_m2(options["deck_section"])
    masses: dict[int, list[float]] = {}

    def add_mass(node: int, m: float, ndf: int, rx: float = 0.0) -> None:
        current = masses.setdefault(node, [0.0] * ndf)
        for d in range(3):
            current[d] += m
        if ndf == 6:
            current[3] += rx

    ops.model("basic", "-ndm", 3, "-ndf", 6)
    # deck spine
    dx = DECK_LENGTH_M / N_DECK_ELEMENTS
    deck_nodes = [deck_node(i) for i in range(N_DECK_ELEMENTS + 1)]
    for i, n in enumerate(deck_nodes):
        ops.node(n, i * dx, 0.0, 0.0)
        trib = dx / 2.0 if i in (0, N_DECK_ELEMENTS) else dx
        add_mass(n, m_deck * trib, 6, ix_deck * trib)
    ops.geomTransf("Linear", 1, 0.0, 0.0, 1.0)
    for i in range(N_DECK_ELEMENTS):
        ops.element(
            "elasticBeamColumn",
            1 + i,
            deck_nodes[i],
            deck_nodes[i + 1],
            deck_area,
            E_STEEL_PA,
            G_STEEL_PA,
            DECK_J_M4 * kt,
            DECK_I_VERTICAL_M4 * ky,
            DECK_I_LATERAL_M4 * kx,
            1,
        )
    # pylon: legs (y = -/+), crossbeam at deck level, strut
    n_leg = N_LEG_BELOW_DECK + N_LEG_ABOVE_DECK
    leg_nodes: dict[int, list[int]] = {}
    tag = PYLON_NODE0
    height = PYLON_TOP_Z_M - PYLON_BASE_Z_M
    apex = PYLON_NODE0 + 99
    ops.node(apex, PYLON_X_M, 0.0, PYLON_TOP_Z_M)
    for side, sign in ((0, -1.0), (1, 1.0)):
        nodes = []
        for k in range(n_leg):
            if k <= N_LEG_BELOW_DECK:
                z = PYLON_BASE_Z_M + k * (-PYLON_BASE_Z_M) / N_LEG_BELOW_DECK
            else:
                z = (k - N_LEG_BELOW_DECK) * PYLON_TOP_Z_M / N_LEG_ABOVE_DECK
            y = sign * PYLON_BASE_HALF_WIDTH_M * (PYLON_TOP_Z_M - z) / height
            ops.node(tag, PYLON_X_M, y, z)
            nodes.append(tag)
            tag += 1
        nodes.append(apex)
        ops.fix(nodes[0], 1, 1, 1, 1, 1, 1)
        leg_nodes[side] = nodes
    ops.geomTransf("Linear", 2, 1.0, 0.0, 0.0)
    etag = 101
    leg_len = []
    for side in (0, 1):
        nodes = leg_nodes[side]
        for k in range(n_leg):
            ops.element(
                "elasticBeamColumn",
                etag,
                nodes[k],
                nodes[k + 1],
                LEG["A"],
                E_STEEL_PA,
                G_STEEL_PA,
                LEG["J"],
                LEG["Iy"],
                LEG["Iz"],
                2,
            )
            etag += 1
            length = float(np.linalg.norm(np.subtract(ops.nodeCoord(nodes[k + 1]), ops.nodeCoord(nodes[k]))))
            leg_len.append((nodes[k], nodes[k + 1], length))
    for a, b, length in leg_len:
        add_mass(a, LEG["mass"] * length / 2.0, 6)
        add_mass(b, LEG["mass"] * length / 2.0, 6)
    cross_mid = tag
    strut_mid = tag + 1
    pylon_nodes = sorted({n for nodes in leg_nodes.values() for n in nodes} | {cross_mid, strut_mid})
    for mid, level, sec in (
        (cross_mid, N_LEG_BELOW_DECK, CROSSBEAM),
        (strut_mid, N_LEG_BELOW_DECK + STRUT_LEVEL, STRUT),
    ):
        z = ops.nodeCoord(leg_nodes[0][level])[2]
        ops.node(mid, PYLON_X_M, 0.0, z)
        for side in (0, 1):
            ops.element(
                "elasticBeamColumn",
                etag,
                leg_nodes[side][level],
                mid,
                sec["A"],
                E_STEEL_PA,
                G_STEEL_PA,
                sec["J"],
                sec["Iy"],
                sec["Iz"],
                2,
            )
            etag += 1
            length = abs(ops.nodeCoord(leg_nodes[side][level])[1])
            add_mass(mid, sec["mass"] * length / 2.0, 6)
            add_mass(leg_nodes[side][level], sec["mass"] * length / 2.0, 6)
    # bearings: zeroLength springs (x shear, y lateral, z vertical, rx torsion)
    i_pylon = N_DECK_ELEMENTS // 2
    supports = (
        (deck_nodes[0], GROUND_NODE0, "abutment"),
        (deck_nodes[-1], GROUND_NODE0 + 1, "abutment"),
        (deck_nodes[i_pylon], cross_mid, "pylon"),
    )
    mat = 1
    for deck_n, base_n, kind in supports:
        if kind == "abutment":
            ops.node(base_n, *ops.nodeCoord(deck_n))
            ops.fix(base_n, 1, 1, 1, 1, 1, 1)
        b = BEARINGS[kind]
        lateral = lateral_stiffness(b, options["lateral_restraint"], kb)
        stiff = (b["shear"] * kb, lateral, b["vertical"] * kb, b["torsion"] * kb)
        mats = []
        for k in stiff:
            ops.uniaxialMaterial("Elastic", mat, k)
            mats.append(mat)
            mat += 1
        ops.element("zeroLength", etag, base_n, deck_n, "-mat", *mats, "-dir", 1, 2, 3, 4)
        etag += 1
    # sensor points on the deck edges (rigid links)
    sdofs = sensor_dofs()
    for _, node, direction, spine, y in sensor_points():
        if direction == 3:  # one node per edge point
            ops.node(node, ops.nodeCoord(spine)[0], y, 0.0)
            ops.rigidLink("beam", spine, node)
    # cables
    cable_elements_by_group: dict[str, list[list[int]]] = {}
    cable_nodes: list[int] = []
    cnode = CABLE_NODE0
    anode = ANCHOR_NODE0
    apex_xyz = np.array(ops.nodeCoord(apex))
    for group, offset in ANCHOR_OFFSETS.items():
        ops.uniaxialMaterial("Elastic", mat, E_CABLE_PA * kc)
        ops.uniaxialMaterial("InitStrainMaterial", mat + 1, mat, eps[group])
        cable_mat = mat + 1
        mat += 2
        cables = []
        for i in (i_pylon - offset, i_pylon + offset):
            for sign in (-1.0, 1.0):
                ops.node(anode, i * dx, sign * ANCHOR_Y_M, 0.0)
                ops.rigidLink("beam", deck_node(i), anode)
                start = np.array(ops.nodeCoord(anode))
                chain = [anode]
                anode += 1
                length = float(np.linalg.norm(apex_xyz - start))
                seg_mass = CABLE_MASS_KG_PER_M * length / cable_elements
                ops.model("basic", "-ndm", 3, "-ndf", 6)
                for s in range(1, cable_elements):
                    xyz = start + (apex_xyz - start) * s / cable_elements
                    ops.node(cnode, *xyz)
                    ops.fix(cnode, 0, 0, 0, 1, 1, 1)
                    chain.append(cnode)
                    cable_nodes.append(cnode)
                    add_mass(cnode, seg_mass, 6)
                    cnode += 1
                chain.append(apex)
                add_mass(deck_node(i), seg_mass / 2.0, 6)
                add_mass(apex, seg_mass / 2.0, 6)
                tags = []
                for a, b in zip(chain[:-1], chain[1:]):
                    ops.element("corotTruss", etag, a, b, CABLE_AREA_M2, cable_mat)
                    tags.append(etag)
                    etag += 1
                cables.append(tags)
        cable_elements_by_group[group] = cables
    # masses and gravity loads
    ops.timeSeries("Linear", 1)
    ops.pattern("Plain", 1, 1)
    for node, m in masses.items():
        ops.mass(node, *m)
        ops.load(node, 0.0, 0.0, -m[0] * GRAVITY_M_PER_S2, 0.0, 0.0, 0.0)
    # rotations of cable interior nodes carry no mass
    return BridgeInfo(
        deck_nodes=deck_nodes,
        pylon_nodes=pylon_nodes,
        cable_nodes=cable_nodes,
        apex=apex,
        pylon_deck_node=deck_nodes[i_pylon],
        cable_elements=cable_elements_by_group,
        masses={n: tuple(m) for n, m in masses.items()},
        sensor_dofs=sdofs,
        sensor_offsets=sensor_offsets(),
        target_tension_n=target,
        initial_strain=dict(eps),
    )
