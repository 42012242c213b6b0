"""Measured modal data: natural frequencies, mode shapes at named DOFs, damping, weights.

File formats (both read and written here; reading goes through :mod:`framework.core.textio`,
so duplicate keys, non-UTF-8 text, oversized files and YAML bombs are errors):

YAML ::

    name: lab_frame            # optional
    units: {frequency: Hz}     # optional; only SI (Hz, damping ratio, m) is accepted
    dofs: [y, x, torsion]      # measured DOF labels (text), in the row order of the shapes
    modes:
      - label: 1st y           # optional text, unique; a number label must be quoted: '1'
        frequency_hz: 3.58     # required, finite, > 0
        damping_ratio: 0.0121  # optional, fraction of critical, 0 <= zeta < 1
        shape: [1.0, 0.004, -0.01]   # optional, one value per DOF, not all zero
        frequency_std_hz: 0.01       # optional, standard deviation of the frequency, >= 0
        shape_std: [0.01, 0.01, 0.01]  # optional, >= 0 (0 at a normalising component)
        weight_frequency: 1.0        # optional, default 1, >= 0
        weight_shape: 1.0            # optional, default 1, >= 0

CSV (UTF-8, ``,`` between columns, ``.`` in numbers): one row per mode, columns
``frequency_hz`` (required), ``label``, ``damping_ratio``, ``frequency_std_hz``,
``weight_frequency``, ``weight_shape`` (optional), ``mode`` (optional, distinct numbers
>= 1, informative only: rows are taken in file order) and one column ``shape:<dof>`` per
measured DOF (optional; all or none). An empty cell is a value not given.

Strict reading (nothing is converted silently): numbers are YAML numbers, never booleans
(``true`` is not 1) or text (``'3.58'``) and must be finite; a list is required where a
list is documented (``dofs: "yx"`` is an error, not ['y', 'x']); labels are text, distinct;
every value error names the file, the field and the value.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from framework.core import textio
from framework.core.errors import InputError

_NUMBER_TYPES = (int, float, np.integer, np.floating)


def _show(value, limit: int = 60) -> str:
    """repr of a value for a message, shortened."""
    text = repr(value)
    if isinstance(value, int) and len(text) > limit:
        return f"{text[:12]}...({len(text)} digits)"
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _kind(value) -> str:
    if isinstance(value, Mapping):
        return "a mapping"
    if isinstance(value, (bool, np.bool_)):
        return "a boolean"
    if isinstance(value, str):
        return "a text"
    if isinstance(value, (list, tuple)):
        return "a list"
    return type(value).__name__


def _number(value, where: str) -> float:
    """A real number as float: bool, text, None and out-of-range integers are InputErrors."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, _NUMBER_TYPES):
        raise InputError(f"{where}: not a number: {_show(value)}")
    try:
        return float(value)
    except OverflowError:
        raise InputError(f"{where}: {_show(value)} is outside the double-precision range") from None


#: value rules: name -> (test, wording)
_RULES = {
    "positive": (lambda a: a > 0, "a finite positive number"),
    "nonnegative": (lambda a: a >= 0, "a finite number >= 0"),
    "ratio": (lambda a: (a >= 0) & (a < 1), "a finite fraction of critical damping in [0, 1)"),
    "any": (lambda a: np.ones_like(a, dtype=bool), "a finite number"),
}


def _check_rule(arr: np.ndarray, where: str, rule: str) -> None:
    test, wording = _RULES[rule]
    finite = np.isfinite(arr)
    ok = finite & test(np.where(finite, arr, 0.0))
    if not np.all(ok):
        bad = arr[~ok][0]
        raise InputError(f"{where}: must be {wording}, got {_show(float(bad))}")


def _check_value(value, where: str, rule: str) -> float:
    x = _number(value, where)
    _check_rule(np.array([x]), where, rule)
    return x


def _check_leaves(values, where: str, depth: int = 0) -> None:
    if isinstance(values, np.ndarray):
        values = values.tolist()
    if isinstance(values, (list, tuple)):
        if depth >= 3:
            raise InputError(f"{where}: nested too deeply: {_show(values)}")
        for v in values:
            _check_leaves(v, where, depth + 1)
        return
    if isinstance(values, (complex, np.complexfloating)):
        raise InputError(f"{where}: must be real (normal modes), got {_show(values)}; make them real first")
    _number(values, where)


def _as_float_array(
    values, where: str, shape: tuple | None = None, rule: str = "any", each: str = ""
) -> np.ndarray:
    """Numbers as a float array of ``shape``; booleans, text, ragged lists and non-finite values
    are InputErrors (np.asarray alone would turn True into 1.0 and '3.5' into 3.5)."""
    if isinstance(values, np.ndarray) and values.dtype.kind in "iuf":
        arr = values.astype(float)
    elif isinstance(values, np.ndarray) and values.dtype.kind == "c":
        raise InputError(f"{where}: must be real (normal modes); make them real first")
    elif isinstance(values, (str, bytes, Mapping)) or not isinstance(values, (list, tuple, np.ndarray)):
        raise InputError(f"{where}: expected a list of numbers, got {_kind(values)}: {_show(values)}")
    else:
        _check_leaves(values, where)
        try:
            arr = np.asarray(values, dtype=float)
        except (TypeError, ValueError, OverflowError):
            raise InputError(f"{where}: not a regular array of numbers: {_show(values)}") from None
    if shape is not None and arr.shape != shape:
        if arr.ndim == 1 and len(shape) == 1:
            each = f" ({each})" if each else ""
            raise InputError(f"{where}: has {arr.size} values, expected {shape[0]}{each}; got {_show(values)}")
        raise InputError(f"{where}: has shape {arr.shape}, expected {shape}")
    _check_rule(arr.ravel(), where, rule)
    return arr


def _not_text(value, where: str) -> str:
    hint = ""
    if isinstance(value, _NUMBER_TYPES) and not isinstance(value, (bool, np.bool_)):
        hint = f"; write it in quotes: '{value}'"
    return f"{where}: must be text, got {_kind(value)}: {_show(value)}{hint}"


def _texts(values, where: str, what: str) -> tuple[str, ...]:
    """A tuple of distinct non-empty texts (DOF or mode labels)."""
    if isinstance(values, (str, bytes, Mapping)) or not isinstance(values, (list, tuple, np.ndarray)):
        raise InputError(f"{where}: must be a list of {what}, got {_kind(values)}: {_show(values)}")
    out = []
    for i, v in enumerate(values):
        if not isinstance(v, str):
            raise InputError(_not_text(v, f"{where}[{i}]"))
        if not v.strip():
            raise InputError(f"{where}[{i}]: must not be empty")
        out.append(str(v))
    dup = sorted(v for v, n in Counter(out).items() if n > 1)
    if dup:
        raise InputError(f"{where}: duplicate {what} {dup}")
    return tuple(out)


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
        if not isinstance(self.name, str):
            raise InputError(f"{src}: name must be text, got {_show(self.name)}")
        if self.meta is not None and not isinstance(self.meta, Mapping):
            raise InputError(f"{src}: meta must be a mapping, got {_kind(self.meta)}")
        object.__setattr__(self, "meta", dict(self.meta or {}))
        f = _as_float_array(self.frequencies_hz, f"{src}: frequencies_hz")
        if f.ndim != 1 or f.size == 0:
            raise InputError(f"{src}: frequencies_hz must be a non-empty list, got {_show(self.frequencies_hz)}")
        for i, v in enumerate(f):
            _check_value(v, f"{src}: mode {i + 1} frequency_hz", "positive")
        object.__setattr__(self, "frequencies_hz", f)
        m = f.size
        dofs = _texts(self.dofs, f"{src}: dofs", "DOF labels")
        object.__setattr__(self, "dofs", dofs)
        if self.shapes is not None:
            shapes = _as_float_array(self.shapes, f"{src}: shapes", (len(dofs), m))
            for j in range(m):
                if not np.any(shapes[:, j]):
                    raise InputError(f"{src}: mode {j + 1} shape is all zeros")
            object.__setattr__(self, "shapes", shapes)
        labels = self.labels if self.labels is not None and len(self.labels) else [f"mode {i + 1}" for i in range(m)]
        labels = _texts(labels, f"{src}: labels", "mode labels")
        if len(labels) != m:
            raise InputError(f"{src}: {len(labels)} labels for {m} modes")
        object.__setattr__(self, "labels", labels)
        rules = {"damping_ratio": "ratio", "weight_frequency": "nonnegative", "weight_shape": "nonnegative",
                 "frequency_std_hz": "nonnegative"}
        for name, rule in rules.items():
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, _as_float_array(value, f"{src}: {name}", (m,), rule))
        if self.shape_std is not None:
            if self.shapes is None:
                raise InputError(f"{src}: shape_std is given but there are no shapes")
            arr = _as_float_array(self.shape_std, f"{src}: shape_std", (len(dofs), m), "nonnegative")
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

    def select(self, indices: Sequence[int]) -> MeasuredModes:
        """Keep the modes at the given 0-based positions (in the given order).

        Each index must be an integer in 0..n_modes-1 and appear once: a negative index does
        not count from the end here. For 1-based mode numbers from a config use
        :meth:`select_modes`.
        """
        idx = self._positions(indices, 0, f"{self.source}: mode indices")
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

    def select_modes(self, numbers: Sequence[int], where: str | None = None) -> MeasuredModes:
        """Keep the modes numbered ``numbers`` (1-based, as in ``measured.modes: [1, 3]``).

        0, negative, repeated or too large numbers, booleans and non-integers are InputErrors
        naming ``where`` (default: the data's source), the value and the number of modes.
        """
        where = where or f"{self.source}: modes"
        return self.select([n - 1 for n in self._positions(numbers, 1, where)])

    def _positions(self, values, first: int, where: str) -> list[int]:
        """Checked positions: integers in first..n_modes-1+first, each once (first = 0 or 1)."""
        m, last = self.n_modes, self.n_modes - 1 + first
        noun, nouns = ("mode", "mode numbers") if first == 1 else ("index", "mode indices")
        if isinstance(values, (str, bytes, Mapping)) or not isinstance(values, (Sequence, np.ndarray)):
            raise InputError(f"{where}: expected a list of {nouns}, got {_kind(values)}: {_show(values)}")
        out: list[int] = []
        for v in values:
            if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)):
                raise InputError(f"{where}: {_show(v)} is not a {noun} (an integer {first} to {last})")
            if not first <= v <= last:
                raise InputError(
                    f"{where}: {noun} {int(v)} does not exist: the data have {m} modes, "
                    f"{'numbered' if first else 'indices'} {first} to {last}"
                )
            if int(v) in out:
                raise InputError(f"{where}: {noun} {int(v)} is selected twice")
            out.append(int(v))
        if not out:
            raise InputError(f"{where}: no modes selected")
        return out

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
        out = {"name": self.name, "dofs": list(self.dofs), "modes": modes}
        if self.meta:
            out["meta"] = _plain(self.meta)
        return out


def _plain(value):
    """Numpy scalars and arrays, tuples and mappings as plain Python data (for YAML)."""
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    if isinstance(value, np.generic):
        return value.item()
    return value


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
#: numeric per-mode fields and their rule (see _RULES)
_MODE_NUMBERS = {
    "frequency_hz": "positive",
    "damping_ratio": "ratio",
    "frequency_std_hz": "nonnegative",
    "weight_frequency": "nonnegative",
    "weight_shape": "nonnegative",
}
#: the only units accepted in data files (SI); anything else is an error, not a guess
_UNITS = {"frequency": "Hz", "damping": "ratio", "shape": "m"}


def from_dict(data: dict, source: str = "<dict>") -> MeasuredModes:
    """Build MeasuredModes from the YAML structure documented in the module docstring."""
    if not isinstance(data, Mapping):
        raise InputError(f"{source}: expected a mapping with 'dofs' and 'modes', got {_kind(data)}")
    unknown = sorted(str(k) for k in set(data) - _TOP_KEYS)
    if unknown:
        raise InputError(f"{source}: unknown top-level key(s) {unknown}; allowed: {sorted(_TOP_KEYS)}")
    units = data.get("units")
    units = {} if units is None else units
    if not isinstance(units, Mapping):
        raise InputError(f"{source}: 'units' must be a mapping like {_UNITS}, got {_show(units)}")
    for key, value in units.items():
        if key not in _UNITS:
            raise InputError(f"{source}: units: unknown quantity {_show(key)}; known: {sorted(_UNITS)}")
        if not isinstance(value, str) or value != _UNITS[key]:
            raise InputError(
                f"{source}: units.{key}: unsupported unit {_show(value)}; data files use {_UNITS[key]!r} (SI)"
            )
    name = data.get("name", Path(source).stem)
    if not isinstance(name, str) or not name.strip():
        raise InputError(f"{source}: name: must be a non-empty text, got {_show(name)}")
    meta = data.get("meta")
    meta = {} if meta is None else meta
    if not isinstance(meta, Mapping):
        raise InputError(f"{source}: meta: must be a mapping, got {_kind(meta)}: {_show(meta)}")
    modes = data.get("modes")
    if not isinstance(modes, list) or not modes:
        raise InputError(f"{source}: 'modes' must be a non-empty list, got {_show(modes)}")
    dofs = data.get("dofs")
    dofs = _texts([] if dofs is None else dofs, f"{source}: dofs", "DOF labels")
    cols: dict[str, list] = {k: [] for k in _MODE_KEYS}
    for j, mode in enumerate(modes):
        where = f"{source}: modes[{j}]"
        if not isinstance(mode, Mapping):
            raise InputError(f"{where}: expected a mapping, got {_kind(mode)}: {_show(mode)}")
        bad = sorted(str(k) for k in set(mode) - _MODE_KEYS)
        if bad:
            raise InputError(f"{where}: unknown key(s) {bad}; allowed: {sorted(_MODE_KEYS)}")
        if mode.get("frequency_hz") is None:
            raise InputError(f"{where}: 'frequency_hz' is required")
        label = mode.get("label")
        if label is not None and not isinstance(label, str):
            raise InputError(_not_text(label, f"{where}.label"))
        for key, rule in _MODE_NUMBERS.items():
            if mode.get(key) is not None:
                _check_value(mode[key], f"{where}.{key}", rule)
        for key, rule in (("shape", "any"), ("shape_std", "nonnegative")):
            if mode.get(key) is not None:
                _as_float_array(mode[key], f"{where}.{key}", (len(dofs),), rule, each="one per DOF")
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
        return [float(v) for v in values] if key in _MODE_NUMBERS else values

    shapes = column("shape")
    shape_std = column("shape_std")
    return MeasuredModes(
        frequencies_hz=np.array(column("frequency_hz"), dtype=float),
        dofs=dofs,
        shapes=None if shapes is None else np.array(shapes, dtype=float).T,
        damping_ratio=column("damping_ratio"),
        labels=tuple(v if v is not None else f"mode {i + 1}" for i, v in enumerate(cols["label"])),
        weight_frequency=column("weight_frequency"),
        weight_shape=column("weight_shape"),
        frequency_std_hz=column("frequency_std_hz"),
        shape_std=None if shape_std is None else np.array(shape_std, dtype=float).T,
        name=name,
        source=source,
        meta=dict(meta),
    )


def load(path: str | Path) -> MeasuredModes:
    """Load measured modes from a .yaml/.yml or .csv file (format in the module docstring)."""
    path = Path(path)
    if path.is_dir():
        raise InputError(f"{path}: is a folder, not a measured-modes file")
    suffix = path.suffix.lower()
    if suffix in (".yaml", ".yml"):
        data = textio.read_yaml_file(path, what="measured-modes", max_bytes=textio.DATA_MAX_BYTES)
        return from_dict(data, source=str(path))
    if suffix == ".csv":
        return _load_csv(path)
    raise InputError(f"{path}: unsupported measured-modes format {suffix!r} (use .yaml or .csv)")


_CSV_NUMBERS = ("frequency_hz", "damping_ratio", "frequency_std_hz", "weight_frequency", "weight_shape")
_CSV_COLUMNS = {"mode", "label", *_CSV_NUMBERS}


def _load_csv(path: Path) -> MeasuredModes:
    """Read the CSV format of the module docstring with :func:`framework.core.textio.read_csv_table`."""
    header, rows = textio.read_csv_table(path, what="measured-modes", max_bytes=textio.DATA_MAX_BYTES)
    src = str(path)
    if "frequency_hz" not in header:
        raise InputError(f"{src}: column 'frequency_hz' is required; columns are {header}")
    shape_cols = [c for c in header if c.startswith("shape:")]
    unknown = sorted(set(header) - _CSV_COLUMNS - set(shape_cols))
    if unknown:
        raise InputError(f"{src}: unknown column(s) {unknown}; allowed: {sorted(_CSV_COLUMNS)} and shape:<dof>")
    if any(c == "shape:" for c in shape_cols):
        raise InputError(f"{src}: column 'shape:' names no DOF; write shape:<dof>")
    if not rows:
        raise InputError(f"{src}: no modes (only a header line)")
    pos = {c: i for i, c in enumerate(header)}
    modes, numbers = [], []
    for line, fields in rows:
        cell = {c: fields[i].strip() for c, i in pos.items()}
        at = f"{src}: line {line}"
        mode: dict = {}
        if cell.get("label"):
            mode["label"] = cell["label"]
        if cell.get("mode"):
            number = textio.parse_number(cell["mode"], f"{at}, column 'mode'")
            if number != int(number) or number < 1 or number in numbers:
                raise InputError(f"{at}, column 'mode': must be a distinct mode number >= 1, got {cell['mode']!r}")
            numbers.append(number)
        if not cell["frequency_hz"]:
            raise InputError(f"{at}, column 'frequency_hz': is empty; every mode needs a frequency")
        for c in _CSV_NUMBERS:
            if cell.get(c):
                where = f"{at}, column {c!r}"
                mode[c] = _check_value(textio.parse_number(cell[c], where), where, _MODE_NUMBERS[c])
        given = [c for c in shape_cols if cell[c]]
        if given and len(given) != len(shape_cols):
            empty = [c for c in shape_cols if not cell[c]]
            raise InputError(f"{at}: shape cells {empty} are empty; give all shape values of a mode or none")
        if given:
            mode["shape"] = [textio.parse_number(cell[c], f"{at}, column {c!r}") for c in shape_cols]
        modes.append(mode)
    data = {"name": path.stem, "dofs": [c.split(":", 1)[1] for c in shape_cols], "modes": modes}
    return from_dict(data, source=src)


def save(modes: MeasuredModes, path: str | Path) -> Path:
    """Write measured modes as YAML (atomically); :func:`load` reads back the same data."""
    from framework.core.io import atomic_write_text

    path = Path(path)
    atomic_write_text(path, textio.dump_yaml(modes.to_dict()))
    return path
