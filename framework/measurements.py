"""Measured modal data: natural frequencies, mode shapes at named DOFs, damping, weights.

File formats (both read and written here):

YAML ::

    name: lab_frame            # optional
    units: {frequency: Hz}     # optional; only SI (Hz, damping ratio, m) is accepted
    dofs: [y, x, torsion]      # measured DOF labels, in the row order of the shapes
    modes:
      - label: 1st y           # optional
        frequency_hz: 3.58     # required, > 0
        damping_ratio: 0.0121  # optional, fraction of critical
        shape: [1.0, 0.004, -0.01]   # optional, one value per DOF
        frequency_std_hz: 0.01       # optional, standard deviation of the frequency
        shape_std: [0.01, 0.01, 0.01]  # optional
        weight_frequency: 1.0        # optional, default 1
        weight_shape: 1.0            # optional, default 1

CSV: one row per mode, columns ``frequency_hz`` (required), ``label``, ``damping_ratio``,
``frequency_std_hz``, ``weight_frequency``, ``weight_shape`` (optional) and one column
``shape:<dof>`` per measured DOF (optional; all or none).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from framework.errors import InputError


def _as_float_array(values, where: str, expected_len: int | None = None) -> np.ndarray:
    try:
        arr = np.asarray(values, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{where}: not numeric: {values!r}") from exc
    if expected_len is not None and arr.shape != (expected_len,):
        raise InputError(
            f"{where}: has {arr.size} values, expected {expected_len} (one per DOF); got {values!r}"
        )
    bad = ~np.isfinite(arr)
    if bad.any():
        raise InputError(f"{where}: non-finite value {arr[bad][0]!r} in {values!r}")
    return arr


@dataclass(frozen=True)
class MeasuredModes:
    """Measured modes of one test configuration.

    frequencies_hz: (m,); shapes: (n_dof, m) at ``dofs`` or None; damping_ratio: (m,)
    or None; weights multiply the frequency and shape terms of the objective;
    *_std are standard deviations (None when unknown).
    """

    frequencies_hz: np.ndarray
    dofs: tuple[str, ...] = ()
    shapes: np.ndarray | None = None
    damping_ratio: np.ndarray | None = None
    labels: tuple[str, ...] = ()
    weight_frequency: np.ndarray | None = None
    weight_shape: np.ndarray | None = None
    frequency_std_hz: np.ndarray | None = None
    shape_std: np.ndarray | None = None
    name: str = "measured"
    source: str = "<memory>"
    meta: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        src = self.source
        f = _as_float_array(self.frequencies_hz, f"{src}: frequencies_hz")
        if f.ndim != 1 or f.size == 0:
            raise InputError(f"{src}: frequencies_hz must be a non-empty list, got {self.frequencies_hz!r}")
        for i, v in enumerate(f):
            if v <= 0:
                raise InputError(f"{src}: mode {i + 1} frequency_hz must be > 0, got {v!r}")
        object.__setattr__(self, "frequencies_hz", f)
        m = f.size
        dofs = tuple(str(d) for d in self.dofs)
        dup = sorted({d for d in dofs if dofs.count(d) > 1})
        if dup:
            raise InputError(f"{src}: duplicate DOF labels {dup}")
        object.__setattr__(self, "dofs", dofs)
        if self.shapes is not None:
            shapes = np.asarray(self.shapes)
            if np.iscomplexobj(shapes):
                raise InputError(f"{src}: shapes must be real (normal modes); make them real first")
            shapes = _as_float_array(shapes, f"{src}: shapes")
            if shapes.ndim != 2 or shapes.shape != (len(dofs), m):
                raise InputError(
                    f"{src}: shapes have shape {shapes.shape}, expected ({len(dofs)} dofs, {m} modes)"
                )
            for j in range(m):
                if not np.any(shapes[:, j]):
                    raise InputError(f"{src}: mode {j + 1} shape is all zeros")
            object.__setattr__(self, "shapes", shapes)
        labels = tuple(self.labels) if self.labels else tuple(f"mode {i + 1}" for i in range(m))
        if len(labels) != m:
            raise InputError(f"{src}: {len(labels)} labels for {m} modes")
        object.__setattr__(self, "labels", labels)
        for name in ("damping_ratio", "weight_frequency", "weight_shape", "frequency_std_hz"):
            value = getattr(self, name)
            if value is None:
                continue
            arr = _as_float_array(value, f"{src}: {name}", expected_len=m)
            if name != "damping_ratio" and np.any(arr < 0):
                raise InputError(f"{src}: {name} must be >= 0, got {arr.tolist()}")
            object.__setattr__(self, name, arr)
        if self.shape_std is not None:
            arr = _as_float_array(self.shape_std, f"{src}: shape_std")
            if arr.shape != (len(dofs), m):
                raise InputError(f"{src}: shape_std has shape {arr.shape}, expected ({len(dofs)}, {m})")
            object.__setattr__(self, "shape_std", arr)

    # -------------------------------------------------------------------------------
    @property
    def n_modes(self) -> int:
        return int(self.frequencies_hz.size)

    @property
    def has_shapes(self) -> bool:
        return self.shapes is not None

    @property
    def w_frequency(self) -> np.ndarray:
        return np.ones(self.n_modes) if self.weight_frequency is None else self.weight_frequency

    @property
    def w_shape(self) -> np.ndarray:
        return np.ones(self.n_modes) if self.weight_shape is None else self.weight_shape

    def select(self, modes: Sequence[int]) -> MeasuredModes:
        """Keep the given 0-based modes."""
        idx = list(modes)
        pick = lambda a: None if a is None else np.asarray(a)[..., idx]  # noqa: E731
        return replace(
            self,
            frequencies_hz=self.frequencies_hz[idx],
            shapes=pick(self.shapes),
            damping_ratio=pick(self.damping_ratio),
            labels=tuple(self.labels[i] for i in idx),
            weight_frequency=pick(self.weight_frequency),
            weight_shape=pick(self.weight_shape),
            frequency_std_hz=pick(self.frequency_std_hz),
            shape_std=pick(self.shape_std),
        )

    def to_dict(self) -> dict:
        modes = []
        for j in range(self.n_modes):
            row: dict = {"label": self.labels[j], "frequency_hz": float(self.frequencies_hz[j])}
            if self.damping_ratio is not None:
                row["damping_ratio"] = float(self.damping_ratio[j])
            if self.shapes is not None:
                row["shape"] = [float(v) for v in self.shapes[:, j]]
            if self.frequency_std_hz is not None:
                row["frequency_std_hz"] = float(self.frequency_std_hz[j])
            if self.shape_std is not None:
                row["shape_std"] = [float(v) for v in self.shape_std[:, j]]
            if self.weight_frequency is not None:
                row["weight_frequency"] = float(self.weight_frequency[j])
            if self.weight_shape is not None:
                row["weight_shape"] = float(self.weight_shape[j])
            modes.append(row)
        return {"name": self.name, "dofs": list(self.dofs), "modes": modes}


# --------------------------------------------------------------------------------------
_MODE_KEYS = {
    "label",
    "frequency_hz",
    "damping_ratio",
    "shape",
    "frequency_std_hz",
    "shape_std",
    "weight_frequency",
    "weight_shape",
}
_TOP_KEYS = {"name", "dofs", "modes", "meta", "units"}
#: the only units accepted in data files (SI); anything else is an error, not a guess
_UNITS = {"frequency": "Hz", "damping": "ratio", "shape": "m"}


def from_dict(data: dict, source: str = "<dict>") -> MeasuredModes:
    """Build MeasuredModes from the YAML structure documented in the module docstring."""
    if not isinstance(data, dict):
        raise InputError(f"{source}: expected a mapping with 'dofs' and 'modes', got {type(data).__name__}")
    unknown = sorted(set(data) - _TOP_KEYS)
    if unknown:
        raise InputError(f"{source}: unknown top-level key(s) {unknown}; allowed: {sorted(_TOP_KEYS)}")
    units = data.get("units") or {}
    if not isinstance(units, dict):
        raise InputError(f"{source}: 'units' must be a mapping like {_UNITS}, got {units!r}")
    for key, value in units.items():
        if key not in _UNITS:
            raise InputError(f"{source}: units.{key}: unknown quantity; known: {sorted(_UNITS)}")
        if str(value) != _UNITS[key]:
            raise InputError(
                f"{source}: units.{key}: unsupported unit {value!r}; data files use {_UNITS[key]!r} (SI)"
            )
    modes = data.get("modes")
    if not isinstance(modes, list) or not modes:
        raise InputError(f"{source}: 'modes' must be a non-empty list, got {modes!r}")
    dofs = data.get("dofs") or []
    if not isinstance(dofs, list):
        raise InputError(f"{source}: 'dofs' must be a list of labels, got {dofs!r}")
    cols: dict[str, list] = {k: [] for k in _MODE_KEYS}
    for j, mode in enumerate(modes):
        where = f"{source}: modes[{j}]"
        if not isinstance(mode, dict):
            raise InputError(f"{where}: expected a mapping, got {mode!r}")
        bad = sorted(set(mode) - _MODE_KEYS)
        if bad:
            raise InputError(f"{where}: unknown key(s) {bad}; allowed: {sorted(_MODE_KEYS)}")
        if "frequency_hz" not in mode:
            raise InputError(f"{where}: 'frequency_hz' is required")
        fval = mode["frequency_hz"]
        if isinstance(fval, bool) or not isinstance(fval, (int, float)):
            raise InputError(f"{where}.frequency_hz: not a number: {fval!r}")
        if not math.isfinite(fval) or fval <= 0:
            raise InputError(f"{where}.frequency_hz: must be a finite positive number, got {fval!r}")
        if "shape" in mode:
            _as_float_array(mode["shape"], f"{where}.shape", expected_len=len(dofs))
        for k in _MODE_KEYS:
            cols[k].append(mode.get(k))

    def column(key: str):
        values = cols[key]
        present = [v is not None for v in values]
        if not any(present):
            return None
        if not all(present):
            missing = [i for i, p in enumerate(present) if not p]
            raise InputError(f"{source}: '{key}' given for some modes but missing for modes {missing}")
        return values

    shapes = column("shape")
    shape_std = column("shape_std")
    return MeasuredModes(
        frequencies_hz=np.array(cols["frequency_hz"], dtype=float),
        dofs=tuple(dofs),
        shapes=None if shapes is None else np.array(shapes, dtype=float).T,
        damping_ratio=column("damping_ratio"),
        labels=tuple(v if v is not None else f"mode {i + 1}" for i, v in enumerate(cols["label"])),
        weight_frequency=column("weight_frequency"),
        weight_shape=column("weight_shape"),
        frequency_std_hz=column("frequency_std_hz"),
        shape_std=None if shape_std is None else np.array(shape_std, dtype=float).T,
        name=str(data.get("name", Path(source).stem)),
        source=source,
        meta=dict(data.get("meta") or {}),
    )


def load(path: str | Path) -> MeasuredModes:
    """Load measured modes from a .yaml/.yml or .csv file (format in the module docstring)."""
    path = Path(path)
    if not path.exists():
        raise InputError(f"measured-modes file not found: {path}")
    if path.stat().st_size == 0:
        raise InputError(f"{path}: file is empty")
    suffix = path.suffix.lower()
    if suffix in (".yaml", ".yml"):
        import yaml

        try:
            data = yaml.safe_load(path.read_text())
        except yaml.YAMLError as exc:
            raise InputError(f"{path}: not valid YAML: {exc}") from exc
        return from_dict(data, source=str(path))
    if suffix == ".csv":
        return _load_csv(path)
    raise InputError(f"{path}: unsupported measured-modes format {suffix!r} (use .yaml or .csv)")


def _load_csv(path: Path) -> MeasuredModes:
    import pandas as pd

    try:
        df = pd.read_csv(path)
    except Exception as exc:  # pandas raises several types for malformed files
        raise InputError(f"{path}: cannot read CSV: {exc}") from exc
    if "frequency_hz" not in df.columns:
        raise InputError(f"{path}: column 'frequency_hz' is required; columns are {list(df.columns)}")
    allowed = {
        "mode",
        "label",
        "frequency_hz",
        "damping_ratio",
        "frequency_std_hz",
        "weight_frequency",
        "weight_shape",
    }
    shape_cols = [c for c in df.columns if str(c).startswith("shape:")]
    unknown = sorted(set(df.columns) - allowed - set(shape_cols))
    if unknown:
        raise InputError(f"{path}: unknown column(s) {unknown}")
    modes = []
    for i, row in df.iterrows():
        mode: dict = {}
        for c in (
            "label",
            "frequency_hz",
            "damping_ratio",
            "frequency_std_hz",
            "weight_frequency",
            "weight_shape",
        ):
            if c in df.columns and not (c != "frequency_hz" and pd.isna(row[c])):
                value = row[c]
                if c != "label":
                    try:
                        value = float(value)
                    except (TypeError, ValueError) as exc:
                        raise InputError(f"{path}: row {i + 1} column {c!r}: not numeric: {value!r}") from exc
                mode[c] = value
        if shape_cols:
            mode["shape"] = [row[c] for c in shape_cols]
        modes.append(mode)
    data = {"name": path.stem, "dofs": [c.split(":", 1)[1] for c in shape_cols], "modes": modes}
    return from_dict(data, source=str(path))


def save(modes: MeasuredModes, path: str | Path) -> Path:
    """Write measured modes as YAML (atomically)."""
    import yaml

    from framework.io import atomic_write_text

    path = Path(path)
    atomic_write_text(path, yaml.safe_dump(modes.to_dict(), sort_keys=False))
    return path
