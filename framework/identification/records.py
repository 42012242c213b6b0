"""Vibration test records: time, input channels, output channels with DOF labels.

A :class:`VibrationRecord` holds uniformly sampled time histories of one test. It is
written and read in two documented formats.

NPZ (``numpy.savez``) keys::

    time_s         (n,)          sample times in s, uniformly spaced
    outputs        (n, n_out)    output channels (e.g. accelerations in m/s^2)
    output_labels  (n_out,)      DOF label of each output channel (str)
    inputs         (n, n_in)     input channels (force in N, base acceleration...); n_in may be 0
    input_labels   (n_in,)       label of each input channel (str)
    name           ()            test name (optional)
    meta_json      ()            JSON object with free metadata (optional)

CSV: optional ``# name: <name>`` and ``# meta: <json>`` comment lines, then a header with
``time_s``, one ``in:<label>`` column per input channel and one ``out:<label>`` column per
output channel, one row per sample. A user's own CSV with other column names is read with
``load(path, time_column=..., input_columns=[...], output_columns=[...])``.
"""

from __future__ import annotations

import io
import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from framework.core.errors import InputError
from framework.core.io import atomic_write_bytes, atomic_write_text

_TIME_RTOL = 1e-6


def _channels(values, n: int, where: str) -> np.ndarray:
    arr = np.asarray(values, dtype=float)
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[0] != n:
        raise InputError(f"{where}: expected an array of shape ({n}, channels), got {arr.shape}")
    bad = ~np.isfinite(arr)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        raise InputError(f"{where}: non-finite value {arr[row, col]!r} at sample {row}, channel {col}")
    return arr


@dataclass(frozen=True)
class VibrationRecord:
    """One test: ``time_s`` (n,), ``outputs`` (n, n_out), ``inputs`` (n, n_in, may be n_in = 0)."""

    time_s: np.ndarray
    outputs: np.ndarray
    output_labels: tuple[str, ...]
    inputs: np.ndarray | None = None
    input_labels: tuple[str, ...] = ()
    name: str = "test"
    meta: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        where = f"record {self.name!r}"
        t = np.asarray(self.time_s, dtype=float)
        if t.ndim != 1 or t.size < 4:
            raise InputError(f"{where}: time_s must be a 1-D array of >= 4 samples, got shape {t.shape}")
        dt = np.diff(t)
        if not np.all(np.isfinite(t)) or dt[0] <= 0 or np.max(np.abs(dt - dt[0])) > _TIME_RTOL * dt[0] + 1e-12:
            raise InputError(f"{where}: time_s must be finite and uniformly increasing (first step {dt[0]!r})")
        object.__setattr__(self, "time_s", t)
        out = _channels(self.outputs, t.size, f"{where}: outputs")
        labels = tuple(str(s) for s in self.output_labels)
        if len(labels) != out.shape[1]:
            raise InputError(f"{where}: {len(labels)} output_labels for {out.shape[1]} output channels")
        object.__setattr__(self, "outputs", out)
        object.__setattr__(self, "output_labels", labels)
        inp = np.zeros((t.size, 0)) if self.inputs is None else _channels(self.inputs, t.size, f"{where}: inputs")
        ilabels = tuple(str(s) for s in self.input_labels)
        if len(ilabels) != inp.shape[1]:
            raise InputError(f"{where}: {len(ilabels)} input_labels for {inp.shape[1]} input channels")
        object.__setattr__(self, "inputs", inp)
        object.__setattr__(self, "input_labels", ilabels)
        for lab in labels + ilabels:
            if (labels + ilabels).count(lab) > 1:
                raise InputError(f"{where}: duplicate channel label {lab!r}")

    @property
    def sampling_hz(self) -> float:
        return float(1.0 / (self.time_s[1] - self.time_s[0]))

    @property
    def n_samples(self) -> int:
        return int(self.time_s.size)

    @property
    def has_inputs(self) -> bool:
        return self.inputs.shape[1] > 0

    def select(self, output_labels: Sequence[str]) -> VibrationRecord:
        """The record with only the named output channels (in the given order)."""
        unknown = [c for c in output_labels if c not in self.output_labels]
        if unknown:
            raise InputError(f"record {self.name!r}: output channel(s) {unknown} not in {list(self.output_labels)}")
        cols = [self.output_labels.index(c) for c in output_labels]
        return VibrationRecord(
            self.time_s,
            self.outputs[:, cols],
            tuple(output_labels),
            self.inputs,
            self.input_labels,
            self.name,
            dict(self.meta),
        )

    def head(self, duration_s: float) -> VibrationRecord:
        """The first ``duration_s`` seconds (for quick tests)."""
        n = int(round(duration_s * self.sampling_hz))
        if n < 4:
            raise InputError(f"record {self.name!r}: duration_s={duration_s!r} keeps fewer than 4 samples")
        return VibrationRecord(
            self.time_s[:n],
            self.outputs[:n],
            self.output_labels,
            self.inputs[:n],
            self.input_labels,
            self.name,
            dict(self.meta),
        )


# ---------------------------------------------------------------------------- writing
def save_npz(record: VibrationRecord, path: str | Path) -> Path:
    """Write the record as NPZ (format in the module docstring), atomically."""
    buf = io.BytesIO()
    np.savez_compressed(
        buf,
        time_s=record.time_s,
        outputs=record.outputs,
        output_labels=np.array(record.output_labels, dtype=str),
        inputs=record.inputs,
        input_labels=np.array(record.input_labels, dtype=str),
        name=np.array(record.name),
        meta_json=np.array(json.dumps(record.meta)),
    )
    atomic_write_bytes(path, buf.getvalue())
    return Path(path)


def save_csv(record: VibrationRecord, path: str | Path) -> Path:
    """Write the record as CSV (format in the module docstring), atomically."""
    header = ["time_s"] + [f"in:{s}" for s in record.input_labels] + [f"out:{s}" for s in record.output_labels]
    data = np.column_stack([record.time_s, record.inputs, record.outputs])
    buf = io.StringIO()
    buf.write(f"# name: {record.name}\n# meta: {json.dumps(record.meta)}\n")
    np.savetxt(buf, data, delimiter=",", header=",".join(header), comments="", fmt="%.9g")
    atomic_write_text(path, buf.getvalue())
    return Path(path)


def save(record: VibrationRecord, path: str | Path) -> Path:
    """Write as NPZ or CSV according to the file suffix."""
    suffix = Path(path).suffix.lower()
    if suffix == ".npz":
        return save_npz(record, path)
    if suffix == ".csv":
        return save_csv(record, path)
    raise InputError(f"{path}: unsupported record format {suffix!r} (use .npz or .csv)")


# ---------------------------------------------------------------------------- reading
def load(
    path: str | Path,
    time_column: str = "time_s",
    input_columns: Sequence[str] | None = None,
    output_columns: Sequence[str] | None = None,
) -> VibrationRecord:
    """Read a record from .npz or .csv.

    CSV: by default inputs are the ``in:<label>`` and outputs the ``out:<label>`` columns;
    ``input_columns``/``output_columns`` name them explicitly for other files (labels are then
    the column names). NPZ: keys as in the module docstring; ``inputs``/``input_labels``,
    ``output_labels``, ``name``, ``meta_json`` are optional.
    """
    path = Path(path)
    if not path.exists():
        raise InputError(f"record file not found: {path}")
    suffix = path.suffix.lower()
    if suffix == ".npz":
        return _load_npz(path)
    if suffix == ".csv":
        return _load_csv(path, time_column, input_columns, output_columns)
    raise InputError(f"{path}: unsupported record format {suffix!r} (use .npz or .csv)")


def _load_npz(path: Path) -> VibrationRecord:
    try:
        data = np.load(path, allow_pickle=False)
    except Exception as exc:  # numpy raises several types for corrupt files
        raise InputError(f"{path}: cannot read NPZ: {exc}") from exc
    with data:
        for key in ("time_s", "outputs"):
            if key not in data:
                raise InputError(f"{path}: key {key!r} is required; keys are {sorted(data.files)}")
        outputs = np.asarray(data["outputs"], dtype=float)
        n_out = 1 if outputs.ndim == 1 else outputs.shape[1]
        out_labels = (
            [str(s) for s in data["output_labels"]]
            if "output_labels" in data
            else [f"out{i + 1}" for i in range(n_out)]
        )
        inputs = data["inputs"] if "inputs" in data else None
        n_in = 0 if inputs is None else (1 if np.ndim(inputs) == 1 else np.shape(inputs)[1])
        in_labels = (
            [str(s) for s in data["input_labels"]] if "input_labels" in data else [f"in{i + 1}" for i in range(n_in)]
        )
        name = str(data["name"]) if "name" in data else path.stem
        meta = json.loads(str(data["meta_json"])) if "meta_json" in data else {}
        return VibrationRecord(data["time_s"], outputs, tuple(out_labels), inputs, tuple(in_labels), name, meta)


def _load_csv(path: Path, time_column, input_columns, output_columns) -> VibrationRecord:
    import pandas as pd

    name, meta = path.stem, {}
    with path.open() as fh:
        for line in fh:
            if not line.startswith("#"):
                break
            key, _, value = line[1:].partition(":")
            if key.strip() == "name":
                name = value.strip()
            elif key.strip() == "meta":
                try:
                    meta = json.loads(value)
                except json.JSONDecodeError as exc:
                    raise InputError(f"{path}: '# meta:' line is not JSON: {value.strip()!r}") from exc
    try:
        df = pd.read_csv(path, comment="#")
    except Exception as exc:  # pandas raises several types for malformed files
        raise InputError(f"{path}: cannot read CSV: {exc}") from exc
    cols = list(df.columns)
    if time_column not in cols:
        raise InputError(f"{path}: time column {time_column!r} not found; columns are {cols}")
    if input_columns is None:
        input_columns = [c for c in cols if str(c).startswith("in:")]
    if output_columns is None:
        output_columns = [c for c in cols if str(c).startswith("out:")]
    missing = [c for c in list(input_columns) + list(output_columns) if c not in cols]
    if missing:
        raise InputError(f"{path}: column(s) {missing} not found; columns are {cols}")
    if not output_columns:
        raise InputError(f"{path}: no output columns ('out:<label>' or output_columns=...); columns are {cols}")
    strip = lambda c, p: c[len(p) :] if c.startswith(p) else c  # noqa: E731
    for c in list(input_columns) + list(output_columns):
        if not pd.api.types.is_numeric_dtype(df[c]):
            raise InputError(f"{path}: column {c!r} is not numeric")
    return VibrationRecord(
        df[time_column].to_numpy(float),
        df[list(output_columns)].to_numpy(float),
        tuple(strip(c, "out:") for c in output_columns),
        df[list(input_columns)].to_numpy(float) if input_columns else None,
        tuple(strip(c, "in:") for c in input_columns),
        name,
        meta,
    )
