"""Mode shapes in the Universal File Format (UFF, .unv/.uff): measured modes in, model modes out.

The datasets are read and written by pyuff (the ``exchange`` extra); this module maps
them to :class:`framework.measured.modes.MeasuredModes` through a
:mod:`framework.measured.mapping` file.

Reading (:func:`read_uff_modes`):

- dataset 55 (data at nodes), analysis type 2 (normal mode): one dataset per mode, in
  file order; frequency (Hz) and viscous damping ratio from record 8, 3 (x, y, z) or 6
  (x, y, z, rx, ry, rz) values per node in global axes; specific data type unknown,
  general, displacement, velocity or acceleration (a shape in velocity or acceleration
  differs from the displacement shape by a factor per mode, which MAC and the scale-free
  shape residuals ignore). Any other analysis type is refused.
- complex shapes (data type 5) are made real with :func:`framework.measured.complex_shapes.real_mode_shape`
  (rotation maximising the real part) after the mapping; the MAC loss of each mode is
  logged and kept in ``meta["complex_to_real_mac_loss"]``.
- dataset 164 (units): the length factor L (file length units per metre: to SI divide by
  L) converts translations and coordinates to metres; rotations are radians. Without
  dataset 164 the file is taken as SI (logged); datasets 164 that disagree are refused.
- datasets 15 and 2411 (nodes): coordinates in metres in ``meta["geometry_m"]``
  ({node: [x, y, z]}, for plotting). Other datasets (58 functions, 82 trace lines, 2412
  elements, ...) are ignored and counted in the log.
- model DOF = sign x value of the mapped test DOF. A mapped node missing from a mode
  dataset, or a mapped DOF that is zero in every mode (a direction the test did not
  measure), is an error naming the file, the dataset and the node. Test DOFs with data
  that the mapping does not name are ignored (count logged). Without a mapping every
  component that is non-zero in some mode is kept under its test label, e.g. ``101+x``.
- mode labels: ID line 4 (the load case / mode name) when it is given, not ``NONE`` and
  distinct for every mode, else ``mode <n>`` with n the mode number of record 7.

Writing (:func:`write_uff_modes`): dataset 164 (SI), dataset 2411 when a geometry is
given, one dataset 55 per mode (analysis type 2, displacement, real). pyuff writes the
values of dataset 55 in E13.5 format, so a write -> read round trip reproduces
frequencies and shapes to 6 significant digits (relative error <= 5e-6).
"""

from __future__ import annotations

import logging
import math
import tempfile
from collections import Counter
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from framework.core.errors import InputError, MissingDependencyError
from framework.measured.complex_shapes import real_mode_shape
from framework.measured.mapping import AXES, ROTATIONS, DofMapping, SensorDof, as_mapping, parse_sensor_dof
from framework.measured.modes import MeasuredModes

log = logging.getLogger(__name__)

#: Datasets this module reads; everything else in a file is skipped.
_USED_SETS = (15, 55, 164, 2411)
_ANALYSIS_TYPES = {
    0: "unknown",
    1: "static",
    2: "normal mode",
    3: "complex eigenvalue first order",
    4: "transient",
    5: "frequency response",
    6: "buckling",
    7: "complex eigenvalue second order",
}
#: Specific data types accepted as mode shapes: unknown, general, displacement, velocity, acceleration.
_SHAPE_DATA_TYPES = {0, 1, 8, 11, 12}
_NONE_ID = {"", "none"}


def _pyuff():
    try:
        import pyuff
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise MissingDependencyError("pyuff is required for UFF files: pip install 'gomu[exchange]'") from exc
    return pyuff


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


# ----------------------------------------------------------------------------------- read
def _read_sets(path: Path) -> list[tuple[int, dict]]:
    """(1-based position in the file, pyuff dict) of the datasets this module uses."""
    pyuff = _pyuff()
    try:
        uff = pyuff.UFF(str(path))
        types = [int(t) for t in uff.get_set_types()]
    except Exception as exc:  # pyuff raises bare Exception
        raise InputError(f"{path}: not a readable universal file: {_one_line(exc)}") from exc
    if not types:
        raise InputError(f"{path}: no UFF datasets found (not a universal file?)")
    out: list[tuple[int, dict]] = []
    ignored: Counter = Counter()
    for i, kind in enumerate(types):
        if kind not in _USED_SETS:
            ignored[kind] += 1
            continue
        try:
            dset = uff.read_sets(i)
        except Exception as exc:  # pyuff raises bare Exception with a generic message
            where = f"{path}: dataset #{i + 1} (type {kind})"
            raise InputError(f"{where}: pyuff cannot parse it: {_one_line(exc)}") from exc
        out.append((i + 1, dset))
    if ignored:
        log.info("%s: ignored datasets (type: count) %s", path, dict(sorted(ignored.items())))
    return out


def _length_factor(path: Path, sets: Sequence[tuple[int, dict]]) -> float:
    """L of dataset 164 (file length units per metre); 1 without dataset 164."""
    factors: dict[float, int] = {}
    for k, d in sets:
        if d["type"] != 164:
            continue
        value = d.get("length")
        if not isinstance(value, float) or not math.isfinite(value) or value <= 0:
            raise InputError(
                f"{path}: dataset #{k} (type 164): length factor {value!r} must be a positive number "
                "(file length units per metre)"
            )
        factors.setdefault(value, k)
    if not factors:
        log.info("%s: no units dataset 164; values taken as SI (m, rad)", path)
        return 1.0
    if len(factors) > 1:
        listed = ", ".join(f"dataset #{k}: {v!r}" for v, k in factors.items())
        raise InputError(f"{path}: units datasets 164 disagree on the length factor ({listed}); refusing to guess")
    return next(iter(factors))


def _geometry(path: Path, sets: Sequence[tuple[int, dict]], length: float) -> dict[int, list[float]]:
    geometry: dict[int, list[float]] = {}
    local = 0
    for k, d in sets:
        if d["type"] not in (15, 2411):
            continue
        coords = np.column_stack([np.asarray(d[c], dtype=float) for c in ("x", "y", "z")]) / length
        nodes = np.asarray(d["node_nums"], dtype=float)
        if not np.all(np.isfinite(coords)):
            bad = int(nodes[np.flatnonzero(~np.isfinite(coords).all(axis=1))[0]])
            raise InputError(f"{path}: dataset #{k} (type {d['type']}): node {bad}: non-finite coordinate")
        local += int(np.sum(~np.isin(np.asarray(d.get("def_cs", []), dtype=float), (0.0, 1.0))))
        for node, xyz in zip(nodes, coords):
            geometry[int(node)] = [float(v) for v in xyz]
    if local:
        log.warning("%s: %d nodes are defined in local coordinate systems; coordinates kept as given", path, local)
    return geometry


class _ModeSet:
    """One dataset 55 checked: mode number, frequency, damping, label and node values (SI)."""

    def __init__(self, path: Path, k: int, d: dict, length: float):
        self.dataset = k
        self.where = f"{path}: dataset #{k} (type 55"
        analysis = d.get("analysis_type")
        if analysis != 2:
            kind = _ANALYSIS_TYPES.get(analysis, "undefined")
            raise InputError(
                f"{self.where}): analysis type {analysis} ({kind}) is not supported; export normal modes "
                "(analysis type 2)"
            )
        self.mode_n = int(d.get("mode_n", 0))
        self.where += f", mode {self.mode_n})"
        spec = d.get("spec_data_type")
        if spec not in _SHAPE_DATA_TYPES:
            raise InputError(
                f"{self.where}: specific data type {spec} is not a mode shape "
                "(expected 0 unknown, 1 general, 8 displacement, 11 velocity or 12 acceleration)"
            )
        self.ndv = int(d.get("n_data_per_node", 0))
        if self.ndv not in (3, 6):
            raise InputError(f"{self.where}: {self.ndv} values per node; expected 3 (x, y, z) or 6 (x..rz)")
        freq = d.get("freq")
        if not isinstance(freq, float) or not math.isfinite(freq) or freq <= 0:
            raise InputError(f"{self.where}: frequency {freq!r} Hz must be a finite positive number")
        self.frequency_hz = freq
        self.damping = float(d.get("modal_damp_vis") or 0.0)
        self.hysteretic = float(d.get("modal_damp_his") or 0.0)
        id4 = str(d.get("id4", "")).strip()
        self.label = None if id4.lower() in _NONE_ID else id4
        nodes = np.asarray(d["node_nums"], dtype=int)
        values = np.column_stack([np.asarray(d[f"r{c + 1}"]) for c in range(self.ndv)])
        values = values.astype(complex if np.iscomplexobj(values) else float)
        if values.shape[0] != nodes.size:
            raise InputError(f"{self.where}: {nodes.size} node numbers but {values.shape[0]} value records")
        values[:, :3] /= length  # translations to metres; rotations stay in radians
        self.complex = bool(np.iscomplexobj(values))
        self.values: dict[int, np.ndarray] = {}
        for node, row in zip(nodes.tolist(), values):
            if node in self.values:
                raise InputError(f"{self.where}: node {node} appears twice")
            if not np.all(np.isfinite(row)):
                raise InputError(f"{self.where}: node {node}: non-finite value in {row.tolist()!r}")
            self.values[node] = row

    def value(self, dof: SensorDof, model_dof: str | None) -> complex | float:
        mapped = f" (test DOF {dof.label!r} -> model DOF {model_dof!r})" if model_dof else ""
        row = self.values.get(dof.node)
        if row is None:
            raise InputError(f"{self.where}: node {dof.node} is missing{mapped}")
        if dof.component >= self.ndv:
            raise InputError(
                f"{self.where}: node {dof.node}: axis {dof.axis} needs 6 values per node, "
                f"the dataset has {self.ndv}{mapped}"
            )
        return dof.sign * row[dof.component]


def _selected_dofs(path: Path, modes: Sequence[_ModeSet], mapping: DofMapping | None):
    """[(test DOF, model DOF label)] to read, and the number of non-zero test DOFs left out."""
    present: set[tuple[int, int]] = set()
    for m in modes:
        for node, row in m.values.items():
            present.update((node, c) for c in np.flatnonzero(row).tolist())
    if mapping is None:
        entries = [(SensorDof(n, AXES[c]), SensorDof(n, AXES[c]).label) for n, c in sorted(present)]
        return entries, 0
    if not mapping.dofs:
        raise InputError(
            f"{mapping.source}: no 'dofs' section (test node + direction -> model DOF) for UFF file {path}"
        )
    mapped = {(s.node, s.component) for s, _ in mapping.dofs}
    return list(mapping.dofs), len(present - mapped)


def read_uff_modes(path: str | Path, mapping: DofMapping | Mapping | str | Path | None = None) -> MeasuredModes:
    """Measured modes from the dataset-55 normal modes of a UFF file (rules in the module docstring).

    mapping: a :class:`DofMapping`, a dict with the mapping-file structure, the path of a
    mapping YAML file, or None (keep every non-zero test DOF under its label ``101+x``).
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"UFF file not found: {path}")
    if path.stat().st_size == 0:
        raise InputError(f"{path}: file is empty")
    mapping = as_mapping(mapping)
    sets = _read_sets(path)
    length = _length_factor(path, sets)
    geometry = _geometry(path, sets, length)
    modes = [_ModeSet(path, k, d, length) for k, d in sets if d["type"] == 55]
    if not modes:
        raise InputError(f"{path}: no mode-shape dataset 55 found")
    entries, unmapped = _selected_dofs(path, modes, mapping)
    if unmapped:
        log.info("%s: %d measured test DOFs not in the mapping were ignored", path, unmapped)
    shapes = np.array([[m.value(dof, label if mapping else None) for m in modes] for dof, label in entries])
    if shapes.size == 0:
        raise InputError(f"{path}: every mode shape is zero")
    for i, (dof, label) in enumerate(entries):
        if not np.any(shapes[i]):
            raise InputError(
                f"{path}: node {dof.node} axis {dof.axis} (test DOF {dof.label!r} -> model DOF {label!r}) is zero "
                "in every mode dataset: a direction this test did not measure? check the mapping"
            )
    meta: dict = {
        "format": "uff",
        "datasets": [m.dataset for m in modes],
        "mode_numbers": [m.mode_n for m in modes],
        "test_dofs": [dof.label for dof, _ in entries],
        "length_factor": length,
        "geometry_m": geometry,
    }
    if np.iscomplexobj(shapes):
        real = np.empty(shapes.shape)
        losses = []
        for j, m in enumerate(modes):
            real[:, j], loss = real_mode_shape(shapes[:, j])
            losses.append(loss)
            level = logging.WARNING if loss > 0.05 else logging.INFO
            log.log(level, "%s: mode %d complex shape made real, MAC loss %.3g", m.where, m.mode_n, loss)
        shapes = real
        meta["complex_to_real_mac_loss"] = losses
    if any(m.hysteretic for m in modes):
        log.info("%s: hysteretic damping of record 8 ignored (viscous damping ratio kept)", path)
    labels = [m.label for m in modes]
    if None in labels or len(set(labels)) != len(labels):
        labels = [f"mode {m.mode_n}" for m in modes]
    damping = np.array([m.damping for m in modes])
    return MeasuredModes(
        frequencies_hz=np.array([m.frequency_hz for m in modes]),
        dofs=tuple(label for _, label in entries),
        shapes=shapes.astype(float),
        damping_ratio=damping if np.any(damping) else None,
        labels=tuple(labels),
        name=path.stem,
        source=str(path),
        meta=meta,
    )


# ---------------------------------------------------------------------------------- write
def _modes_arrays(modes) -> tuple[np.ndarray, np.ndarray, tuple[str, ...], list[str], np.ndarray]:
    shapes = getattr(modes, "shapes", None)
    if shapes is None:
        raise InputError("write_uff_modes: the modes have no shapes to write")
    freqs = np.asarray(modes.frequencies_hz, dtype=float)
    shapes = np.asarray(shapes, dtype=float)
    dofs = tuple(modes.dofs)
    labels = list(getattr(modes, "labels", ()) or [f"mode {j + 1}" for j in range(freqs.size)])
    damping = getattr(modes, "damping_ratio", None)
    damping = np.zeros(freqs.size) if damping is None else np.asarray(damping, dtype=float)
    if not (np.all(np.isfinite(freqs)) and np.all(np.isfinite(shapes)) and np.all(np.isfinite(damping))):
        raise InputError("write_uff_modes: frequencies, shapes and damping must be finite")
    return freqs, shapes, dofs, labels, damping


def _id_line(text: str) -> str:
    line = " ".join(str(text).split())[:80]
    return line or "NONE"


def _geometry_set(pyuff, geometry: Mapping, nodes: Sequence[int]) -> dict:
    table = {}
    for node, xyz in geometry.items():
        try:
            n = int(node)
            x, y, z = (float(v) for v in xyz)
        except (TypeError, ValueError) as exc:
            raise InputError(f"write_uff_modes: geometry[{node!r}] must be node: [x, y, z] in m, got {xyz!r}") from exc
        if not all(math.isfinite(v) for v in (x, y, z)):
            raise InputError(f"write_uff_modes: geometry[{node!r}]: non-finite coordinate {xyz!r}")
        table[n] = (x, y, z)
    missing = sorted(set(nodes) - set(table))
    if missing:
        log.warning("write_uff_modes: %d mode-shape nodes have no coordinates: %s", len(missing), missing[:10])
    order = sorted(table)
    xyz = np.array([table[n] for n in order], dtype=float).reshape(-1, 3)
    zeros = np.zeros(len(order), dtype=int)
    return pyuff.prepare_2411(
        node_nums=np.array(order, dtype=int),
        def_cs=zeros,
        disp_cs=zeros,
        color=np.ones(len(order), dtype=int),
        x=xyz[:, 0].copy(),
        y=xyz[:, 1].copy(),
        z=xyz[:, 2].copy(),
    )


def write_uff_modes(
    path: str | Path,
    modes,
    mapping: DofMapping | Mapping | str | Path | None = None,
    geometry: Mapping[int, Sequence[float]] | None = None,
    *,
    name: str | None = None,
) -> Path:
    """Write modes (a ModalResult or MeasuredModes) as UFF datasets 164 (SI), 2411 and 55.

    mapping: test node + direction -> model DOF, as for reading; every mapped model DOF
    must be among ``modes.dofs`` (others are not written, count logged). Without a mapping
    the DOF labels must be test DOFs such as ``101+x``. geometry: {node: [x, y, z]} in m
    (default: ``modes.meta["geometry_m"]`` when present). name: ID line 1 (default: the
    modes' name). Returns the path; the file is replaced atomically.
    """
    from framework import __version__
    from framework.core.io import atomic_write_bytes

    pyuff = _pyuff()
    freqs, shapes, dofs, labels, damping = _modes_arrays(modes)
    mapping = as_mapping(mapping)
    if mapping is None:
        entries = [
            (parse_sensor_dof(d, "write_uff_modes (no mapping given, so DOF labels must be test DOFs)"), d)
            for d in dofs
        ]
        source = "write_uff_modes"
    else:
        entries = list(mapping.dofs)
        source = mapping.source
        if not entries:
            raise InputError(f"{source}: no 'dofs' section (test node + direction -> model DOF) to write UFF")
    index = {d: i for i, d in enumerate(dofs)}
    missing = [label for _, label in entries if label not in index]
    if missing:
        raise InputError(f"{source}: model DOF(s) {missing} not among the modes' DOFs {list(dofs)}")
    skipped = len(set(dofs) - {label for _, label in entries})
    if skipped:
        log.info("write_uff_modes: %d model DOFs not in the mapping are not written", skipped)
    nodes = sorted({s.node for s, _ in entries})
    row = {n: i for i, n in enumerate(nodes)}
    ndv = 6 if any(s.axis in ROTATIONS for s, _ in entries) else 3
    if geometry is None:
        geometry = (getattr(modes, "meta", None) or {}).get("geometry_m")
    model_name = _id_line(name or getattr(modes, "name", "") or "gomu model")
    sets = [
        pyuff.prepare_164(
            units_code=1, units_description="SI", temp_mode=1, length=1.0, force=1.0, temp=1.0, temp_offset=273.15
        )
    ]
    if geometry:
        sets.append(_geometry_set(pyuff, geometry, nodes))
    for j in range(freqs.size):
        values = np.zeros((len(nodes), ndv))
        for s, label in entries:
            values[row[s.node], s.component] = s.sign * shapes[index[label], j]
        # E13.5 has room for a 3-digit exponent only without the separating blank: write such
        # numerical zeros as 0 so that readers splitting on blanks also read the file
        values[np.abs(values) < 1e-99] = 0.0
        components = {f"r{c + 1}": values[:, c].copy() for c in range(ndv)}
        sets.append(
            pyuff.prepare_55(
                id1=model_name,
                id2=_id_line(f"mode shapes written by gomu {__version__}"),
                id3="NONE",
                id4=_id_line(labels[j]),
                id5="NONE",
                model_type=1,
                analysis_type=2,
                data_ch=2 if ndv == 3 else 3,
                spec_data_type=8,
                data_type=2,
                n_data_per_node=ndv,
                node_nums=np.array(nodes, dtype=int),
                load_case=1,
                mode_n=j + 1,
                freq=float(freqs[j]),
                modal_m=0.0,
                modal_damp_vis=float(damping[j]),
                modal_damp_his=0.0,
                **components,
            )
        )
    path = Path(path)
    with tempfile.TemporaryDirectory() as tmp:
        scratch = Path(tmp) / "modes.uff"
        pyuff.UFF(str(scratch)).write_sets(sets, mode="overwrite")
        data = scratch.read_bytes()
    atomic_write_bytes(path, data)
    return path
