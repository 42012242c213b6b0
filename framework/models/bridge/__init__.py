"""Cable-stayed pedestrian bridge (SPEC section 6): OpenSeesPy model, modes, measured data.

Structure: 59.5 m continuous steel-box deck over two 29.75 m spans, a central A-shaped
steel pylon 22.4 m high and six pairs of stays (12 cables, 32 mm) anchored ~8 m apart on
both deck edges and at the pylon apex. Axes: x along the bridge (0 at the north abutment,
pylon at 29.75 m), y transverse, z up; deck centroid (spine) at z = 0.

Model (built by :func:`build_bridge`, run through :class:`~framework.models.opensees.OpenSeesModel`):

- deck: 48 ``elasticBeamColumn`` elements (Linear transformation) on the spine, fully
  composite section transformed to steel (E = 200 GPa, G = 77 GPa): I = 0.00439 m^4
  (vertical bending, local y), 0.06140 m^4 (lateral bending, local z), J = 0.00810 m^4;
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
- masses: from the section (:data:`DECK_MASS_ITEMS`, 1462 kg/m, rotational inertia
  873 kg m^2/m about the spine), lumped at the spine nodes; pylon 328 kg/m; no mass on
  constrained (rigid-link) nodes; rotational inertia only about the deck axis;
- gravity: nodal loads m g, one-step Newton (UmfPack) on the corotational model, then
  eigen (OpenSees default solver, ~100 modes) on the deformed, stressed state; modes are
  classified by kinetic-energy share (deck, cables, pylon) and direction.

Evaluation paths: ``make_model(fast=False)`` is the plain :class:`OpenSeesModel`;
``fast=True`` (default) is :class:`framework.models.bridge.fast.BridgeFastModel`, same
build and gravity, own eigen solution (~12x faster, same modes to ~1e-10).

Options (keyword arguments of :func:`make_model` / :func:`build_bridge`):

- ``cable_elements`` (1, 2, 4, 8; default 4): elements per cable. One element loses the
  2nd vertical mode (deck-cable coupled, cables swinging laterally).
- ``lateral_restraint`` ("guided" default | "shear"): lateral stiffness of the bearings.
  With "shear" (k_y = shear stiffness) the deck sways as a rigid body at about 1.3 Hz, far
  below the measured lateral modes (4.86, 5.33 Hz), so the bearings must be laterally
  guided: "guided" uses k_y = vertical stiffness (steel guides / shear keys, stiff as the
  bearing in compression).
- ``tensions`` ("installed" default | "final"): "installed" applies 55/95/75 kN as the
  initial strain before gravity (the deck weight then raises them); "final" iterates the
  initial strain (``final_iterations`` outer gravity runs) until the dead-load tensions
  equal 55/95/75 kN. See docs/bridge.md for the comparison.
- ``deck_energy_min`` (default 0.1): modes whose deck share of kinetic energy is below this
  are cable or pylon modes and are dropped, and so are longitudinal deck modes (both
  paths). The cable-dominated partner of the split 1st vertical pair has a deck share of
  only 0.12, hence the low threshold.

Updating parameters (ratios to initial values, bounds 0.6-1.3): ``K_y_deck`` (vertical
bending I), ``K_x_deck`` (lateral bending I), ``K_t_deck`` (torsion J), ``K_cable`` (E A of
all cables, tension kept), ``T_Cab1`` (tension of the four Cab-1 cables), ``K_bearing``
(all bearing springs together).

Measured data (:func:`measured`): the 8 subspace-identified frequencies. Measured mode
shapes are not published; the reference shapes at the 36 deck sensor DOFs are the
initial (4-element) model's deck modes paired with the measured modes by type and
nearest frequency, so the MAC term guards mode identity only.
"""

from __future__ import annotations

import functools
import logging
import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from framework.correlation import pair_modes
from framework.errors import InputError, ModelEvaluationError
from framework.measurements import MeasuredModes
from framework.models.base import ModalResult
from framework.models.opensees import GravityAnalysis, OpenSeesModel, run_static
from framework.parameters import Parameter, ParameterSet

log = logging.getLogger(__name__)

GRAVITY_M_PER_S2 = 9.81

# --- geometry ----------------------------------------------------------------------
DECK_LENGTH_M = 59.5
N_DECK_ELEMENTS = 48
PYLON_X_M = DECK_LENGTH_M / 2.0
PYLON_BASE_Z_M = -4.0
PYLON_TOP_Z_M = 18.4
PYLON_BASE_HALF_WIDTH_M = 2.4
N_LEG_BELOW_DECK = 4
N_LEG_ABOVE_DECK = 14
STRUT_LEVEL = 7  # leg element index above deck level of the upper strut (z = 9.2 m)
ANCHOR_Y_M = 1.175  # edge pipes' centre lines
SENSOR_Y_M = 1.175
#: deck element offsets of the anchors from the pylon node: Cab-3, Cab-2, Cab-1
ANCHOR_OFFSETS = {"Cab-3": 6, "Cab-2": 13, "Cab-1": 19}
#: sensor stations (deck node indices): 9 stations, quarter and mid points of both spans
SENSOR_NODES = (6, 12, 18, 21, 24, 27, 30, 36, 42)

# --- materials and sections --------------------------------------------------------
E_STEEL_PA = 200e9
G_STEEL_PA = 77e9
E_CABLE_PA = 165e9
RHO_STEEL_KG_PER_M3 = 7850.0
DECK_AREA_M2 = 0.108  # transformed to steel
DECK_I_VERTICAL_M4 = 0.00439
DECK_I_LATERAL_M4 = 0.06140
DECK_J_M4 = 0.00810
#: 400WC328 legs, strong axis (local z) bending in the plane of the A-frame
LEG = {"A": 0.0418, "Iy": 0.48e-3, "Iz": 1.97e-3, "J": 1.8e-5, "mass": 328.0}
#: crossbeam at deck level carrying the pivot bearings: also 400WC328
CROSSBEAM = dict(LEG)
#: upper strut: 200x200x10 SHS
STRUT = {"A": 7.42e-3, "Iy": 4.39e-5, "Iz": 4.39e-5, "J": 7.0e-5, "mass": 58.3}
CABLE_DIAMETER_M = 0.032
CABLE_AREA_M2 = math.pi * CABLE_DIAMETER_M**2 / 4.0
CABLE_MASS_KG_PER_M = RHO_STEEL_KG_PER_M3 * CABLE_AREA_M2
DESIGN_TENSION_N = {"Cab-1": 55e3, "Cab-2": 95e3, "Cab-3": 75e3}

#: bearing springs per support line (two bearings together)
BEARINGS = {
    "abutment": {"shear": 2.58e6, "vertical": 1.60e8, "torsion": 8.86e8},
    "pylon": {"shear": 1.86e6, "vertical": 7.70e7, "torsion": 3.90e6},
}

#: Deck mass estimate per metre: (item, kg/m, y of centroid m, z of centroid m, own r^2 m^2).
#: Steel box: trapezoid 1.40 m top, 0.90 m bottom, 0.47 m deep, 16 mm plates
#: (perimeter 3.364 m -> 0.0538 m^2); 10 % for diaphragms and stiffeners; concrete slab
#: 2.20 m x 0.13 m between the pipes at 2500 kg/m^3; pipes 250x150x9 (6876 mm^2 each);
#: grout fills each pipe's void around a 100 mm duct (22770 mm^2 each, 2300 kg/m^3);
#: railings 1.4 m high, 35 kg/m per side. Items on both edges are listed once with their
#: total mass and |y|.
DECK_MASS_ITEMS = (
    ("steel box", 422.5, 0.0, -0.25, 0.20),
    ("diaphragms, stiffeners", 42.2, 0.0, -0.25, 0.20),
    ("concrete slab", 715.0, 0.0, 0.06, 2.20**2 / 12.0),
    ("edge pipes", 108.0, ANCHOR_Y_M, 0.0, 0.005),
    ("grout in pipes", 104.8, ANCHOR_Y_M, 0.0, 0.003),
    ("railings", 70.0, 1.25, 0.80, 0.16),
)


def deck_mass_per_m() -> tuple[float, float]:
    """Deck mass (kg/m) and mass moment of inertia about the spine (kg m^2/m).

    m = sum m_i; I_x = sum m_i (y_i^2 + z_i^2 + r_i^2) over :data:`DECK_MASS_ITEMS`.
    """
    m = sum(item[1] for item in DECK_MASS_ITEMS)
    ix = sum(item[1] * (item[2] ** 2 + item[3] ** 2 + item[4]) for item in DECK_MASS_ITEMS)
    return m, ix


PARAMETER_NAMES = ("K_y_deck", "K_x_deck", "K_t_deck", "K_cable", "T_Cab1", "K_bearing")
_DESCRIPTIONS = {
    "K_y_deck": "deck vertical bending stiffness ratio (I about transverse axis)",
    "K_x_deck": "deck lateral bending stiffness ratio (I about vertical axis)",
    "K_t_deck": "deck torsional stiffness ratio (J)",
    "K_cable": "axial stiffness ratio E A of all cables (tensions kept)",
    "T_Cab1": "tension ratio of the four Cab-1 cables (nearest the abutments)",
    "K_bearing": "stiffness ratio of all bearing springs together",
}


def bridge_parameters(lower: float = 0.6, upper: float = 1.3) -> ParameterSet:
    """The six updating parameters, ratios to the initial model (initial 1)."""
    return ParameterSet(Parameter(name, 1.0, lower, upper, "-", _DESCRIPTIONS[name]) for name in PARAMETER_NAMES)


# --- node numbering ----------------------------------------------------------------
DECK_NODE0 = 1  # deck spine nodes 1..49
PYLON_NODE0 = 101  # legs, crossbeam and strut mid nodes
GROUND_NODE0 = 301
ANCHOR_NODE0 = 401  # deck anchors (rigid-link slaves)
SENSOR_NODE0 = 501  # deck edge sensor points (rigid-link slaves)
CABLE_NODE0 = 1001  # cable interior nodes


@dataclass
class BridgeInfo:
    """What :func:`build_bridge` created (tags, masses), used by postprocess and fast path."""

    deck_nodes: list[int]
    pylon_nodes: list[int]
    cable_nodes: list[int]
    apex: int
    pylon_deck_node: int
    cable_elements: dict[str, list[list[int]]]  # group -> cables -> element tags
    masses: dict[int, tuple[float, ...]]  # node -> nodal mass per DOF
    sensor_dofs: dict[str, tuple[int, int]]
    sensor_offsets: dict[str, tuple[int, float]]  # label -> (spine node, y of the edge)
    target_tension_n: dict[str, float]
    initial_strain: dict[str, float] = field(default_factory=dict)
    tension_n: dict[str, float] = field(default_factory=dict)


def deck_node(i: int) -> int:
    return DECK_NODE0 + i


def _sensors() -> list[tuple[str, int, int, int, float]]:
    """(label, sensor node, direction, spine node, y of the edge) of every measured DOF:
    vertical (uz) and lateral (uy) at both edges (E: y < 0, W: y > 0) of 9 stations."""
    out = []
    for k, (i, side, y) in enumerate(
        (i, side, y) for i in SENSOR_NODES for side, y in (("E", -SENSOR_Y_M), ("W", SENSOR_Y_M))
    ):
        for comp, direction in (("uz", 3), ("uy", 2)):
            out.append((f"d{i:02d}{side}_{comp}", SENSOR_NODE0 + k, direction, deck_node(i), y))
    return out


def sensor_dofs() -> dict[str, tuple[int, int]]:
    """Measured DOFs {label: (sensor node, direction)} (see :func:`_sensors`)."""
    return {label: (node, direction) for label, node, direction, _, _ in _sensors()}


def _sensor_offsets() -> dict[str, tuple[int, float]]:
    return {label: (spine, y) for label, _, _, spine, y in _sensors()}


def _check_options(cable_elements: int, lateral_restraint: str, tensions: str) -> None:
    if cable_elements not in (1, 2, 4, 8):
        raise InputError(f"bridge option cable_elements must be 1, 2, 4 or 8, got {cable_elements!r}")
    if lateral_restraint not in ("guided", "shear"):
        raise InputError(f"bridge option lateral_restraint must be 'guided' or 'shear', got {lateral_restraint!r}")
    if tensions not in ("installed", "final"):
        raise InputError(f"bridge option tensions must be 'installed' or 'final', got {tensions!r}")


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
    lateral_restraint: str = "guided",
    tensions: str = "installed",
    final_iterations: int = 3,
    initial_strain: Mapping[str, float] | None = None,
) -> BridgeInfo:
    """Create the bridge in the OpenSees domain for parameter ratios ``values``.

    With ``tensions="final"`` the initial strain of each cable group is corrected by
    eps0 <- eps0 + (T_target - T) / (E A) over ``final_iterations`` gravity runs (each
    rebuilding the domain) before the final build; the mean axial force over each group's
    elements is its tension T.
    """
    _check_options(cable_elements, lateral_restraint, tensions)
    from framework.models.opensees import ops_module

    ops = ops_module()
    ea_n = E_CABLE_PA * float(values["K_cable"]) * CABLE_AREA_M2
    target = _target_tensions(values)
    eps = dict(initial_strain) if initial_strain else _cable_group_strains(ea_n, target)
    if tensions == "final" and initial_strain is None:
        for _ in range(final_iterations):
            ops.wipe()
            info = _build(ops, values, cable_elements, lateral_restraint, eps, target)
            run_static(ops, GRAVITY)
            force = cable_tensions(ops, info)
            eps = {g: eps[g] + (target[g] - force[g]) / ea_n for g in eps}
        ops.wipe()
    return _build(ops, values, cable_elements, lateral_restraint, eps, target)


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


def _build(ops, values, cable_elements, lateral_restraint, eps, target) -> BridgeInfo:
    ky = float(values["K_y_deck"])
    kx = float(values["K_x_deck"])
    kt = float(values["K_t_deck"])
    kb = float(values["K_bearing"])
    kc = float(values["K_cable"])
    m_deck, ix_deck = deck_mass_per_m()
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
            DECK_AREA_M2,
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
        lateral = b["vertical"] if lateral_restraint == "guided" else b["shear"]
        stiff = (b["shear"], lateral, b["vertical"], b["torsion"])
        mats = []
        for k in stiff:
            ops.uniaxialMaterial("Elastic", mat, k * kb)
            mats.append(mat)
            mat += 1
        ops.element("zeroLength", etag, base_n, deck_n, "-mat", *mats, "-dir", 1, 2, 3, 4)
        etag += 1
    # sensor points on the deck edges (rigid links)
    sdofs = sensor_dofs()
    for _, node, direction, spine, y in _sensors():
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
        sensor_offsets=_sensor_offsets(),
        target_tension_n=target,
        initial_strain=dict(eps),
    )


# --- mode classification -----------------------------------------------------------
MODE_TYPES = ("vertical", "lateral", "torsional", "longitudinal")


def _groups(info: BridgeInfo) -> dict[str, list[int]]:
    deck = set(info.deck_nodes)
    cable = set(info.cable_nodes)
    pylon = [n for n in info.masses if n not in deck and n not in cable]
    return {"deck": info.deck_nodes, "cable": info.cable_nodes, "pylon": pylon}


def energy_shares(vectors: Mapping[int, np.ndarray], info: BridgeInfo) -> dict[str, np.ndarray]:
    """Kinetic-energy shares of each mode: E_g / E with E_g = sum_(nodes in g) m_d phi_d^2.

    ``vectors[node]`` is the (n_modes, 6) eigenvector block of a node with mass. Also
    returns the deck's split by direction (ux, uy, uz, rx), used to name the mode type.
    """
    total = None
    out: dict[str, np.ndarray] = {}
    for group, nodes in _groups(info).items():
        e = 0.0
        for n in nodes:
            m = np.asarray(info.masses[n])
            e = e + vectors[n][:, : m.size] ** 2 @ m
        out[group] = np.asarray(e, dtype=float)
        total = out[group] if total is None else total + out[group]
    deck_dir = np.zeros((total.size, 4))
    for n in info.deck_nodes:
        m = np.asarray(info.masses[n])
        deck_dir += vectors[n][:, :4] ** 2 * m[:4]
    shares = {f"{g}_energy": e / total for g, e in out.items()}
    kind = np.argmax(deck_dir[:, [2, 1, 3, 0]], axis=1)
    shares["mode_type"] = np.array(MODE_TYPES, dtype=object)[kind]
    return shares


def classify_and_keep_deck_modes(
    result: ModalResult, info: BridgeInfo, ops, deck_energy_min: float = 0.1
) -> ModalResult:
    """OpenSeesModel postprocess: classify modes by kinetic energy, keep deck modes."""
    n = result.n_modes
    vectors = {node: np.array([ops.nodeEigenvector(node, j + 1) for j in range(n)]) for node in info.masses}
    shares = energy_shares(vectors, info)
    meta = dict(result.meta)
    meta["cable_tension_n"] = cable_tensions(ops, info)
    meta["target_tension_n"] = dict(info.target_tension_n)
    return keep_deck_modes(result.frequencies_hz, result.shapes, result.dofs, shares, deck_energy_min, meta)


#: deck mode types the test could identify (vertical and lateral shakers and sensors);
#: longitudinal deck modes (e.g. the deck floating on its bearings at 1.3 Hz) are dropped:
#: their small vertical components at the sensors look like the 1st vertical mode
MEASURABLE_TYPES = ("vertical", "lateral", "torsional")


def keep_deck_modes(freqs, shapes, dofs, shares, deck_energy_min, meta) -> ModalResult:
    """ModalResult of the deck modes: deck energy share >= deck_energy_min and a type in
    :data:`MEASURABLE_TYPES`."""
    keep = np.flatnonzero((shares["deck_energy"] >= deck_energy_min) & np.isin(shares["mode_type"], MEASURABLE_TYPES))
    if keep.size == 0:
        raise ModelEvaluationError("too_few_modes", "no deck mode among the computed modes")
    info = {k: np.asarray(v)[keep] for k, v in shares.items()}
    info["model_mode"] = keep + 1
    meta = dict(meta)
    meta["n_modes_computed"] = int(np.size(freqs))
    return ModalResult(np.asarray(freqs)[keep], np.asarray(shapes)[:, keep], dofs, mode_info=info, meta=meta)


# --- model factory and measured data -----------------------------------------------
#: modes solved by the plain path per cable discretisation (cable modes crowd the band)
N_MODES_PLAIN = {1: 40, 2: 70, 4: 100, 8: 180}
#: deck modes above this frequency are dropped (both paths), Hz
F_MAX_HZ = 15.0


def _postprocess(result, info, ops, *, deck_energy_min: float, f_max_hz: float):
    if result.frequencies_hz[-1] < f_max_hz:
        log.debug("plain path: highest computed mode %.2f Hz < f_max %.2f Hz", result.frequencies_hz[-1], f_max_hz)
    keep = result.frequencies_hz <= f_max_hz
    trimmed = ModalResult(result.frequencies_hz[keep], result.shapes[:, keep], result.dofs, meta=result.meta)
    return classify_and_keep_deck_modes(trimmed, info, ops, deck_energy_min)


def make_model(
    cable_elements: int = 4,
    fast: bool = True,
    *,
    lateral_restraint: str = "guided",
    tensions: str = "installed",
    deck_energy_min: float = 0.1,
    f_max_hz: float = F_MAX_HZ,
    n_modes: int | None = None,
):
    """The bridge model: fast path (:class:`BridgeFastModel`) or plain :class:`OpenSeesModel`.

    Both return only deck modes (deck kinetic-energy share >= deck_energy_min) up to
    f_max_hz, with mode_info deck/cable/pylon_energy, mode_type and model_mode.
    """
    _check_options(cable_elements, lateral_restraint, tensions)
    build = functools.partial(
        build_bridge, cable_elements=cable_elements, lateral_restraint=lateral_restraint, tensions=tensions
    )
    plain = OpenSeesModel(
        build=build,
        parameters=bridge_parameters(),
        measured_dofs=sensor_dofs(),
        n_modes=n_modes or N_MODES_PLAIN[cable_elements],
        gravity=GRAVITY,
        solver="",
        postprocess=functools.partial(_postprocess, deck_energy_min=deck_energy_min, f_max_hz=f_max_hz),
        name=f"bridge_{cable_elements}el",
    )
    if not fast:
        return plain
    from framework.models.bridge.fast import BridgeFastModel

    return BridgeFastModel(plain, deck_energy_min=deck_energy_min, f_max_hz=f_max_hz)


#: measured modes (subspace identification), SPEC section 6
MEASURED_HZ = (1.64, 1.90, 3.69, 4.86, 5.33, 6.31, 7.42, 8.32)
MEASURED_PEAK_HZ = (1.64, 1.90, 3.66, 4.85, 5.36, 6.32, 7.42, 8.33)
MEASURED_DAMPING = (0.0022, 0.0087, 0.0052, 0.0081, 0.0061, 0.0049, 0.0096, 0.0143)
MEASURED_LABELS = (
    "1st vertical",
    "2nd vertical (cable-coupled)",
    "3rd vertical",
    "1st horizontal",
    "2nd horizontal",
    "4th vertical",
    "5th vertical",
    "1st torsional",
)
MEASURED_TYPES = ("vertical", "vertical", "vertical", "lateral", "lateral", "vertical", "vertical", "torsional")
#: the source's initial (design) model, another FE package
DESIGN_MODEL_HZ = (1.66, 1.88, 3.88, 5.28, 5.45, 6.79, 7.76, 8.66)


def pair_by_type(result: ModalResult, f_hz=MEASURED_HZ, types=MEASURED_TYPES) -> np.ndarray:
    """Model deck-mode index for each measured mode: nearest frequency among the model's
    deck modes of the same type (vertical, lateral, torsional), one-to-one; -1 if none."""
    out = -np.ones(len(types), dtype=int)
    f_hz = np.asarray(f_hz, dtype=float)
    for kind in set(types):
        rows = [j for j, t in enumerate(types) if t == kind]
        cands = np.flatnonzero(result.mode_info["mode_type"] == kind)
        if cands.size == 0:
            continue
        pairing = pair_modes(result.frequencies_hz[cands], f_hz[rows], method="frequency")
        for j, a in zip(rows, pairing.analytical_index):
            out[j] = cands[a] if a >= 0 else -1
    return out


@functools.lru_cache(maxsize=4)
def _reference_shapes(cable_elements: int) -> tuple[np.ndarray, tuple[str, ...], tuple[float, ...]]:
    model = make_model(cable_elements=cable_elements, fast=False)
    result = model.modal({})
    idx = pair_by_type(result)
    if np.any(idx < 0):
        raise ModelEvaluationError("too_few_modes", f"initial model lacks measured mode types: {idx.tolist()}")
    return result.shapes[:, idx].copy(), result.dofs, tuple(result.frequencies_hz[idx])


def measured(case: str = "base") -> MeasuredModes:
    """The 8 measured modes (subspace frequencies, damping) with reference shapes.

    Measured shapes are not published: the shapes are the initial 4-element model's deck
    modes (paired by type and order) at the 36 edge sensor DOFs, so the MAC term only
    guards mode identity. case: "base" (subspace) or "peak" (peak-picking frequencies).
    """
    if case not in ("base", "peak"):
        raise InputError(f"bridge measured(case=...) must be 'base' or 'peak', got {case!r}")
    shapes, dofs, f_model = _reference_shapes(4)
    return MeasuredModes(
        frequencies_hz=np.array(MEASURED_HZ if case == "base" else MEASURED_PEAK_HZ),
        dofs=dofs,
        shapes=shapes,
        damping_ratio=np.array(MEASURED_DAMPING),
        labels=MEASURED_LABELS,
        name=f"bridge_{case}",
        source="SPEC section 6 (frequencies); shapes from the initial 4-element model",
        meta={
            "shapes": "reference shapes from the initial 4-element model, not measured",
            "mode_types": list(MEASURED_TYPES),
            "design_model_hz": list(DESIGN_MODEL_HZ),
            "initial_model_hz": list(f_model),
        },
    )
