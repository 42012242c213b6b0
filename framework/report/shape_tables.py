"""Mode-shape and correlation tables of a model against measured modes, at named points.

``shape_tables(problem, {"initial": theta0, "updated": theta1})`` returns:

- ``geometry``: one row per node (``kind`` node: tag, x, y, z, group) and per element
  (``kind`` element: tag, ``nodes`` as space-separated tags, group), in the model's length
  unit (``unit``); empty for a model without geometry;
- ``mode_shapes``: state x model mode x node: f_hz, mode_type, ux, uy, uz, each mode scaled
  so that its largest node translation is 1 (dimensionless);
- ``sensor_shapes``: state x measured mode x sensor point: the paired model mode (the
  objective's pairing; for an unmatched mode the model mode of highest MAC, ``matched``
  False), f_measured_hz, f_model_hz, mac, the point's position and the displacements
  measured_u* (measured shape scaled by the modal scale factor
  MSF = phi_e' phi_a / phi_e' phi_e onto the model's) and model_u*, in the scale of
  ``mode_shapes``; ``layout`` is "geometry", or "channels" when the model has no geometry
  (then x is the channel number and u_x the shape value at that DOF);
- ``mac_matrix``: ``kind`` measured_vs_model (state: every measured mode i x every model
  mode j), auto_measured, auto_model (state): i, label_i, f_i_hz, j, label_j, f_j_hz, mac,
  MAC = |phi_i' phi_j|^2 / ((phi_i' phi_i)(phi_j' phi_j)) at the measured DOFs;
- ``comac``: state x measured DOF: COMAC over the matched pairs
  (:func:`framework.core.correlation.comac`), n_pairs, and the DOF's sensor position (NaN where
  the DOF is not a translation at a node, e.g. a rotation).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from framework.core.correlation import comac, mac_matrix
from framework.models.geometry import GeometryHook, ModelShapes, model_shapes

TABLES = ("geometry", "mode_shapes", "sensor_shapes", "mac_matrix", "comac")


def shape_tables(problem, states: dict[str, np.ndarray], structure: str = "",
                 geometry: GeometryHook | None = None) -> dict[str, pd.DataFrame]:
    """The five tables (module docstring) of ``problem`` at each named point theta (physical);
    ``geometry``: the structure's geometry hook, if it has one (:mod:`framework.models.geometry`)."""
    out: dict[str, list] = {t: [] for t in TABLES}
    measured = problem.measured
    geometry_done = False
    for state, theta in states.items():
        theta = np.asarray(theta, float)
        shapes = model_shapes(problem.model, problem.parameters.as_dict(theta), structure, geometry)
        corr = problem.correlation_at(theta)
        if not geometry_done and shapes.has_geometry:
            out["geometry"] = geometry_rows(shapes)
            geometry_done = True
        out["mode_shapes"] += mode_shape_rows(state, shapes)
        if measured.has_shapes:
            out["sensor_shapes"] += sensor_rows(state, shapes, measured, corr)
            out["comac"] += comac_rows(state, shapes, measured, corr)
        out["mac_matrix"] += mac_rows(state, shapes, measured)
    if measured.has_shapes:
        e = np.real(measured.shapes)
        labels = _labels(measured)
        out["mac_matrix"] += _matrix_rows("auto_measured", "measured", e, e, labels, labels,
                                          measured.frequencies_hz, measured.frequencies_hz)
    tables = {name: pd.DataFrame(rows) for name, rows in out.items()}
    for name in ("mode_shapes", "sensor_shapes"):  # shapes scaled to 1: 5 decimals are plenty for figures
        df = tables[name]
        cols = [c for c in df.columns if c in ("ux", "uy", "uz") or c.startswith(("measured_u", "model_u"))]
        tables[name][cols] = df[cols].round(5) if cols else df[cols]
    return tables


def _labels(measured) -> list[str]:
    return list(measured.labels) if measured.labels else [f"mode {i + 1}" for i in range(measured.n_modes)]


def _model_labels(shapes: ModelShapes) -> list[str]:
    types = shapes.mode_types
    return [f"model {j + 1}" + (f" ({types[j]})" if types is not None and types[j] else "")
            for j in range(shapes.frequencies_hz.size)]


def _norms(shapes: ModelShapes) -> np.ndarray:
    """Per mode: the largest node translation (or DOF value without geometry)."""
    if shapes.node_shapes is not None:
        mag = np.sqrt(np.nansum(shapes.node_shapes**2, axis=1))
        n = np.nanmax(mag, axis=0)
    else:
        n = np.max(np.abs(shapes.dof_shapes), axis=0)
    return np.where(n > 0, n, 1.0)


def geometry_rows(shapes: ModelShapes) -> list[dict]:
    rows = [{"kind": "node", "tag": int(t), "x": c[0], "y": c[1], "z": c[2], "nodes": "",
             "group": shapes.node_groups.get(int(t), ""), "unit": shapes.length_unit}
            for t, c in zip(shapes.node_tags, shapes.coords)]
    rows += [{"kind": "element", "tag": e, "x": np.nan, "y": np.nan, "z": np.nan,
              "nodes": " ".join(map(str, nodes)), "group": group, "unit": shapes.length_unit}
             for e, nodes, group in shapes.elements]
    return rows


def mode_shape_rows(state: str, shapes: ModelShapes) -> list[dict]:
    if shapes.node_shapes is None:
        return []
    norms = _norms(shapes)
    rows = []
    for j, f in enumerate(shapes.frequencies_hz):
        u = shapes.node_shapes[:, :, j] / norms[j]
        mtype = "" if shapes.mode_types is None else str(shapes.mode_types[j])
        for t, (ux, uy, uz) in zip(shapes.node_tags, u):
            rows.append({"state": state, "mode": j + 1, "f_hz": float(f), "mode_type": mtype, "node": int(t),
                         "ux": ux, "uy": uy, "uz": uz})
    return rows


def _paired(corr, mm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Paired model mode per measured mode (best MAC where unmatched) and whether it is matched."""
    index = np.asarray(corr.analytical_index, int).copy()
    matched = np.asarray(corr.matched, bool) & (index >= 0)
    for i in np.flatnonzero(index < 0):
        index[i] = int(np.argmax(mm[i])) if mm is not None else 0
    return index, matched


def sensor_rows(state: str, shapes: ModelShapes, measured, corr) -> list[dict]:
    model_index = {d: i for i, d in enumerate(shapes.dofs)}
    cols = [model_index[d] for d in measured.dofs]
    A = shapes.dof_shapes[cols]
    E = np.real(measured.shapes)
    mm = mac_matrix(A, E)
    index, matched = _paired(corr, mm)
    norms = _norms(shapes)
    labels = _labels(measured)
    rows = []
    geometric = shapes.T is not None and shapes.T.size > 0
    if geometric:
        Tm = shapes.T[:, :, cols]
        used = np.flatnonzero(np.abs(Tm).sum(axis=(1, 2)) > 0)
    for i in range(measured.n_modes):
        j = int(index[i])
        a, e = A[:, j], E[:, i]
        scale = float(e @ a) / float(e @ e) if float(e @ e) > 0 else 0.0  # MSF onto the model's shape
        head = {"state": state, "measured_mode": i + 1, "measured_label": labels[i],
                "f_measured_hz": float(measured.frequencies_hz[i]), "model_mode": j + 1,
                "f_model_hz": float(shapes.frequencies_hz[j]), "mac": float(mm[i, j]), "matched": bool(matched[i])}
        if geometric:
            meas = np.einsum("pcd,d->pc", Tm, scale * e) / norms[j]
            model = np.einsum("pcd,d->pc", shapes.T, shapes.dof_shapes[:, j]) / norms[j]
            for p in used:
                x, y, z = shapes.point_coords[p]
                rows.append({**head, "layout": "geometry", "point": shapes.points[p], "x": x, "y": y, "z": z,
                             **{f"measured_u{c}": meas[p, k] for k, c in enumerate("xyz")},
                             **{f"model_u{c}": model[p, k] for k, c in enumerate("xyz")}})
        else:
            for d, label in enumerate(measured.dofs):
                rows.append({**head, "layout": "channels", "point": label, "x": float(d + 1), "y": 0.0, "z": 0.0,
                             "measured_ux": scale * e[d] / norms[j], "measured_uy": 0.0, "measured_uz": 0.0,
                             "model_ux": a[d] / norms[j], "model_uy": 0.0, "model_uz": 0.0})
    return rows


def _matrix_rows(kind, state, phi_i, phi_j, labels_i, labels_j, f_i, f_j) -> list[dict]:
    mm = mac_matrix(phi_j, phi_i)  # rows: modes of phi_i, columns: modes of phi_j
    return [{"kind": kind, "state": state, "i": a + 1, "label_i": labels_i[a], "f_i_hz": float(f_i[a]),
             "j": b + 1, "label_j": labels_j[b], "f_j_hz": float(f_j[b]), "mac": float(mm[a, b])}
            for a in range(mm.shape[0]) for b in range(mm.shape[1])]


def mac_rows(state: str, shapes: ModelShapes, measured) -> list[dict]:
    dofs = measured.dofs if measured.has_shapes else shapes.dofs
    model_index = {d: i for i, d in enumerate(shapes.dofs)}
    A = shapes.dof_shapes[[model_index[d] for d in dofs]]
    f_a, labels_a = shapes.frequencies_hz, _model_labels(shapes)
    rows = []
    if measured.has_shapes:
        rows += _matrix_rows("measured_vs_model", state, np.real(measured.shapes), A, _labels(measured), labels_a,
                             measured.frequencies_hz, f_a)
    rows += _matrix_rows("auto_model", state, A, A, labels_a, labels_a, f_a, f_a)
    return rows


def comac_rows(state: str, shapes: ModelShapes, measured, corr) -> list[dict]:
    model_index = {d: i for i, d in enumerate(shapes.dofs)}
    A = shapes.dof_shapes[[model_index[d] for d in measured.dofs]]
    E = np.real(measured.shapes)
    index, matched = _paired(corr, mac_matrix(A, E))
    pairs = np.flatnonzero(matched)
    values = comac(A[:, index[pairs]], E[:, pairs]) if pairs.size else np.full(len(measured.dofs), np.nan)
    where = _dof_positions(shapes, [model_index[d] for d in measured.dofs])
    return [{"state": state, "dof": dof, "comac": float(values[k]), "n_pairs": int(pairs.size),
             "x": where[k][0], "y": where[k][1], "z": where[k][2]} for k, dof in enumerate(measured.dofs)]


def _dof_positions(shapes: ModelShapes, cols: list[int]) -> list[tuple[float, float, float]]:
    """Position of the sensor point a DOF alone moves (NaN when several or none do)."""
    nan = (np.nan, np.nan, np.nan)
    if shapes.T is None or shapes.T.size == 0:
        return [nan] * len(cols)
    out = []
    for c in cols:
        points = np.flatnonzero(np.abs(shapes.T[:, :, c]).sum(axis=1) > 0)
        out.append(tuple(float(v) for v in shapes.point_coords[points[0]]) if points.size == 1 else nan)
    return out
