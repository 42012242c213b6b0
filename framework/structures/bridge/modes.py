"""Modes of the bridge: kinetic-energy classification, deck-mode selection, pairing by type.

A mode's kinetic energy splits over node groups (deck spine, cable interior nodes, pylon);
the deck's share and the direction that dominates the deck's energy (uz, uy, rx, ux: vertical,
lateral, torsional, longitudinal) classify it. Only measurable deck modes are kept.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from framework.core.correlation import pair_modes
from framework.core.errors import ModelEvaluationError
from framework.models.base import ModalResult
from framework.structures.bridge.build import cable_tensions
from framework.structures.bridge.data import MEASURED_HZ, MEASURED_TYPES
from framework.structures.bridge.geometry import BridgeInfo

MODE_TYPES = ("vertical", "lateral", "torsional", "longitudinal")


def node_groups(info: BridgeInfo) -> dict[str, list[int]]:
    """Nodes with mass by group: deck spine, cable interior nodes, pylon (all others)."""
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
    for group, nodes in node_groups(info).items():
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
