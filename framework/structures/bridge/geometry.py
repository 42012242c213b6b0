"""Geometry, member sections and bearings of the cable-stayed footbridge (SPEC section 6).

Structure: 59.5 m continuous steel-box deck over two 29.75 m spans, a central A-shaped
steel pylon 22.4 m high and six pairs of stays (12 cables, 32 mm) anchored ~8 m apart on
both deck edges and at the pylon apex. Axes: x along the bridge (0 at the north abutment,
pylon at 29.75 m), y transverse, z up; deck centroid (spine) at z = 0. SI units (m, Pa, kg).

The deck's cross-section, its area and masses are in :mod:`.section`. Also the node
numbering of the OpenSees model, the 36 measured (sensor) DOFs and :class:`BridgeInfo`,
the record of what :func:`~framework.structures.bridge.build.build_bridge` created.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from framework.structures.bridge.section import (
    GIVEN_I_LATERAL_M4,
    GIVEN_I_VERTICAL_M4,
    GIVEN_J_M4,
    RHO_STEEL_KG_PER_M3,
)

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
E_CABLE_PA = 165e9
#: the given fully composite deck section, transformed to steel (SPEC 6); the deck's area
#: and masses follow from our reading of the section (:mod:`.section`)
DECK_I_VERTICAL_M4 = GIVEN_I_VERTICAL_M4
DECK_I_LATERAL_M4 = GIVEN_I_LATERAL_M4
DECK_J_M4 = GIVEN_J_M4
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

#: bearing springs per support line (two bearings 450 mm apart together): shear (longitudinal),
#: vertical, torsional (SPEC 6; K_rot = k_bearing L^2 / 2 with k_bearing = vertical / 2, L = 0.45 m
#: at the pylon)
BEARINGS = {
    "abutment": {"shear": 2.58e6, "vertical": 1.60e8, "torsion": 8.86e8},
    "pylon": {"shear": 1.86e6, "vertical": 7.70e7, "torsion": 3.90e6},
}

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
    """Node tag of deck spine node ``i`` (0 at the north abutment, 48 at the south one)."""
    return DECK_NODE0 + i


def sensor_points() -> list[tuple[str, int, int, int, float]]:
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
    """Measured DOFs {label: (sensor node, direction)} (see :func:`sensor_points`)."""
    return {label: (node, direction) for label, node, direction, _, _ in sensor_points()}


def sensor_offsets() -> dict[str, tuple[int, float]]:
    """Measured DOFs {label: (spine node, y of the edge)} (see :func:`sensor_points`)."""
    return {label: (spine, y) for label, _, _, spine, y in sensor_points()}
