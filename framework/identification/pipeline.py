"""Identification chain: record -> (decimate) -> subspace poles -> stability -> modes.

``identify(record, settings)`` runs input-output N4SID on records with inputs and
covariance-driven SSI on output-only records (or the method named in the settings);
``peak_picking(records)`` is the frequency-domain route; ``compare_to_truth`` pairs
identified modes with the true modes of the simulating model; ``to_measured_modes``
exports modes in the framework's measured-modes format.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
import scipy.signal
from pydantic import BaseModel, ConfigDict, Field, field_validator

from framework.core.correlation import mac_matrix
from framework.core.errors import InputError
from framework.identification.frf import FRF, h1_frf, pick_peaks
from framework.identification.records import VibrationRecord
from framework.identification.stability import SelectedModes, select_modes, stability_table
from framework.identification.subspace import Poles, n4sid_poles, real_shape, ssi_cov_poles
from framework.measured.modes import MeasuredModes

log = logging.getLogger(__name__)


class IdentificationSettings(BaseModel):
    """Run parameters of one subspace identification (unknown keys rejected)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    method: str = "auto"  # "auto" (n4sid with inputs, ssi_cov without), "n4sid", "ssi_cov"
    orders: tuple[int, ...] = tuple(range(6, 41, 2))
    block_rows: int = Field(20, ge=2)
    decimate: int = Field(4, ge=1)
    freq_tol: float = Field(0.01, gt=0, lt=1)
    mac_min: float = Field(0.9, ge=0, le=1)
    damping_max: float = Field(0.2, gt=0, lt=1)
    band_hz: tuple[float, float] | None = None
    min_fraction: float = Field(0.5, gt=0, le=1)
    max_spread: float = Field(0.0025, gt=0)
    mpc_min: float = Field(0.5, ge=0, le=1)
    channels: tuple[str, ...] | None = None  # output channels to use (default: all)
    free_decay: bool = False  # output-only record is a free decay: biased correlations

    @field_validator("method")
    @classmethod
    def _method(cls, v: str) -> str:
        if v not in ("auto", "n4sid", "ssi_cov"):
            raise ValueError(f"method must be 'auto', 'n4sid' or 'ssi_cov', got {v!r}")
        return v

    @field_validator("orders")
    @classmethod
    def _orders(cls, v: tuple[int, ...]) -> tuple[int, ...]:
        if len(v) < 2 or min(v) < 1 or list(v) != sorted(set(v)):
            raise ValueError(f"orders must be >= 2 increasing positive integers, got {list(v)}")
        return v


@dataclass(frozen=True)
class Identification:
    """Result of :func:`identify` for one record."""

    record_name: str
    method: str
    sampling_hz: float
    poles: Poles
    stability: pd.DataFrame
    selected: SelectedModes
    settings: IdentificationSettings
    meta: dict = field(default_factory=dict)


def decimate(x: np.ndarray, factor: int) -> np.ndarray:
    """Zero-phase FIR low-pass and keep every ``factor``-th sample (scipy.signal.decimate)."""
    if factor == 1:
        return np.asarray(x, float)
    return scipy.signal.decimate(np.asarray(x, float), factor, ftype="fir", zero_phase=True, axis=0)


def identify(record: VibrationRecord, settings: IdentificationSettings | None = None, **overrides) -> Identification:
    """Subspace identification of ``record`` over the model orders, stability, mode selection."""
    s = settings or IdentificationSettings()
    if overrides:
        s = IdentificationSettings(**{**s.model_dump(), **overrides})
    method = s.method
    if method == "auto":
        method = "n4sid" if record.has_inputs else "ssi_cov"
    if method == "n4sid" and not record.has_inputs:
        raise InputError(f"identify: record {record.name!r} has no input channels; use method='ssi_cov'")
    fs = record.sampling_hz / s.decimate
    labels = record.output_labels
    cols = list(range(len(labels)))
    if s.channels is not None:
        unknown = [c for c in s.channels if c not in labels]
        if unknown:
            raise InputError(f"identify: channels {unknown} not in record {record.name!r} outputs {list(labels)}")
        cols = [labels.index(c) for c in s.channels]
        labels = tuple(s.channels)
    y = decimate(record.outputs[:, cols], s.decimate)
    if method == "n4sid":
        u = decimate(record.inputs, s.decimate)
        poles = n4sid_poles(u, y, fs, s.orders, s.block_rows, labels)
    else:
        poles = ssi_cov_poles(y, fs, s.orders, s.block_rows, labels, s.free_decay)
    band = s.band_hz or (0.0, 0.45 * fs)
    stab = stability_table(poles, s.freq_tol, s.mac_min, s.damping_max, band)
    sel = select_modes(poles, stab, s.freq_tol, s.min_fraction, s.max_spread, s.mpc_min)
    log.info(
        "%s %s: %d modes at %s Hz",
        record.name,
        method,
        len(sel.table),
        np.round(sel.table["frequency_hz"].to_numpy(), 3).tolist(),
    )
    return Identification(record.name, method, fs, poles, stab, sel, s)


def peak_picking(
    records: VibrationRecord | Sequence[VibrationRecord],
    band_hz: tuple[float, float] | None = None,
    n_segments: int = 5,
    overlap: float = 0.5,
    **kwargs,
) -> tuple[FRF, pd.DataFrame, SelectedModes]:
    """H1 FRF averaged over the records (Welch: ``n_segments``, ``overlap``), peaks
    (``kwargs`` go to :func:`pick_peaks`), and the accepted peaks as modes (shape = real part
    of the rotated FRF column at the peak bin, damping by the half-power method, NaN when the
    peak is narrower than a frequency line)."""
    frf = h1_frf(records, n_segments=n_segments, overlap=overlap)
    peaks = pick_peaks(frf, band_hz=band_hz, **kwargs)
    acc = peaks[peaks["accepted"]].reset_index(drop=True)
    shapes = []
    for fp in acc["frequency_hz"]:
        k = int(np.argmin(np.abs(frf.frequency_hz - fp)))
        shapes.append(real_shape(frf.h[k, :, 0]))
    table = pd.DataFrame(
        {
            "mode": np.arange(1, len(acc) + 1),
            "frequency_hz": acc["frequency_hz"].to_numpy(),
            "damping_ratio": acc["damping_ratio"].to_numpy(),
            "coherence": acc["coherence"].to_numpy(),
        }
    )
    shp = np.array(shapes).T if shapes else np.zeros((len(frf.output_labels), 0))
    return frf, peaks, SelectedModes(table, shp, frf.output_labels)


def compare_to_truth(
    selected: SelectedModes,
    f_true_hz: np.ndarray,
    zeta_true: np.ndarray,
    shapes_true: np.ndarray,
    labels: Sequence[str] | None = None,
    freq_window: float = 0.05,
    mac_pair_min: float = 0.5,
) -> pd.DataFrame:
    """One row per true mode: the identified mode within +-freq_window (relative) of highest
    MAC, if that MAC exceeds ``mac_pair_min`` (else the true mode counts as not found).

    Columns: mode, label, f_true_hz, f_identified_hz, f_error_pct, zeta_true,
    zeta_identified, zeta_error_pct, mac_to_true, stable ("yes" when found, else "no"),
    identified_mode (1-based number of the paired identified mode, NaN when not found).
    Identified modes paired with no true mode are added as rows with label "spurious".
    """
    f_true = np.asarray(f_true_hz, float)
    zt = np.broadcast_to(np.asarray(zeta_true, float), f_true.shape)
    phi_t = np.asarray(shapes_true, float)
    if phi_t.shape != (selected.shapes.shape[0], f_true.size):
        raise InputError(
            f"compare_to_truth: shapes_true has shape {phi_t.shape}, expected "
            f"({selected.shapes.shape[0]} channels, {f_true.size} modes)"
        )
    labels = list(labels) if labels is not None else [f"mode {i + 1}" for i in range(f_true.size)]
    f_id = selected.table["frequency_hz"].to_numpy()
    z_id = selected.table["damping_ratio"].to_numpy()
    macs = mac_matrix(selected.shapes, phi_t) if f_id.size else np.zeros((f_true.size, 0))
    rows, used = [], set()
    for i in range(f_true.size):
        cand = [
            j
            for j in range(f_id.size)
            if abs(f_id[j] - f_true[i]) <= freq_window * f_true[i] and macs[i, j] > mac_pair_min and j not in used
        ]
        j = max(cand, key=lambda c: macs[i, c]) if cand else None
        if j is not None:
            used.add(j)
        fi = f_id[j] if j is not None else np.nan
        zi = z_id[j] if j is not None else np.nan
        rows.append(
            {
                "mode": i + 1,
                "label": labels[i],
                "f_true_hz": f_true[i],
                "f_identified_hz": fi,
                "f_error_pct": 100 * (fi - f_true[i]) / f_true[i],
                "zeta_true": zt[i],
                "zeta_identified": zi,
                "zeta_error_pct": 100 * (zi - zt[i]) / zt[i] if zt[i] else np.nan,
                "mac_to_true": macs[i, j] if j is not None else np.nan,
                "stable": "yes" if j is not None else "no",
                "identified_mode": j + 1 if j is not None else np.nan,
            }
        )
    for j in range(f_id.size):
        if j not in used:
            rows.append(
                {
                    "mode": np.nan,
                    "label": "spurious",
                    "f_true_hz": np.nan,
                    "f_identified_hz": f_id[j],
                    "zeta_identified": z_id[j],
                    "stable": "yes",
                    "identified_mode": j + 1,
                }
            )
    return pd.DataFrame(
        rows,
        columns=[
            "mode",
            "label",
            "f_true_hz",
            "f_identified_hz",
            "f_error_pct",
            "zeta_true",
            "zeta_identified",
            "zeta_error_pct",
            "mac_to_true",
            "stable",
            "identified_mode",
        ],
    )


def to_measured_modes(
    selected: SelectedModes,
    name: str = "identified",
    labels: Sequence[str] | None = None,
    dofs: Sequence[str] | None = None,
    source: str = "system identification",
) -> MeasuredModes:
    """Identified modes as :class:`MeasuredModes` (shapes at the output channels as DOFs).

    ``dofs`` renames the channels (same order); a ``frequency_std_hz`` column of the
    selection table (scatter over model orders or tests) becomes the frequency std.
    """
    t = selected.table
    if len(t) == 0:
        raise InputError(f"to_measured_modes: no identified modes for {name!r}")
    dofs = tuple(dofs) if dofs is not None else selected.output_labels
    if len(dofs) != selected.shapes.shape[0]:
        raise InputError(f"to_measured_modes: {len(dofs)} dofs for {selected.shapes.shape[0]} channels")
    damping = t["damping_ratio"].to_numpy(float)
    std = t["frequency_std_hz"].to_numpy(float) if "frequency_std_hz" in t else None
    return MeasuredModes(
        frequencies_hz=t["frequency_hz"].to_numpy(float),
        dofs=dofs,
        shapes=selected.shapes,
        damping_ratio=None if np.isnan(damping).any() else damping,
        labels=tuple(labels) if labels is not None else (),
        frequency_std_hz=None if std is None or np.isnan(std).any() else std,
        name=name,
        source=source,
    )


def average_identifications(runs: Sequence[SelectedModes], freq_tol: float = 0.02) -> SelectedModes:
    """Mean of repeated tests: modes of every run matched to the first run's by frequency
    (within freq_tol) and MAC; frequency/damping averaged, std over runs, shapes sign-aligned
    and averaged. A mode missing from any run is dropped."""
    if not runs:
        raise InputError("average_identifications: no runs")
    ref = runs[0]
    rows, shapes = [], []
    for i, f0 in enumerate(ref.table["frequency_hz"]):
        fs, zs, ps = [f0], [ref.table["damping_ratio"].iloc[i]], [ref.shapes[:, i]]
        for run in runs[1:]:
            f = run.table["frequency_hz"].to_numpy()
            cand = np.flatnonzero(np.abs(f - f0) <= freq_tol * f0)
            if cand.size == 0:
                break
            m = mac_matrix(run.shapes[:, cand], ref.shapes[:, [i]])[0]
            j = cand[int(np.argmax(m))]
            fs.append(f[j])
            zs.append(run.table["damping_ratio"].iloc[j])
            p = run.shapes[:, j]
            ps.append(p if p @ ref.shapes[:, i] >= 0 else -p)
        else:
            rows.append(
                {
                    "frequency_hz": float(np.mean(fs)),
                    "damping_ratio": float(np.mean(zs)),
                    "frequency_std_hz": float(np.std(fs, ddof=1)) if len(fs) > 1 else 0.0,
                    "damping_std": float(np.std(zs, ddof=1)) if len(zs) > 1 else 0.0,
                    "n_tests": len(fs),
                }
            )
            shapes.append(real_shape(np.mean(ps, axis=0)))
    table = pd.DataFrame(rows)
    table.insert(0, "mode", np.arange(1, len(table) + 1))
    return SelectedModes(table, np.array(shapes).T if shapes else np.zeros((ref.shapes.shape[0], 0)), ref.output_labels)
