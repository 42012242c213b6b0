"""Rows of the identification tables from the results of one run (plain, JSON-able dicts).

Every row starts with ``record``: the record's name (``lab_sweep_1``), ``mean`` for the mean
of the identifications of a test's records, or ``average`` for peak picking on the H1
averaged over the records. The run kind adds the run key and the setting columns.

- ``modes``: record x true mode (plus ``spurious`` rows for identified modes paired with no
  true mode): mode, mode_label, f_true_hz, f_identified_hz, f_error_pct, zeta_true,
  zeta_identified, zeta_error_pct, mac_to_true, stable ("yes" when found), identified_mode,
  deck_energy (bridge: the true mode's kinetic-energy share of the deck);
- ``identified``: record x identified mode: mode, frequency_hz, damping_ratio and the
  method's own columns (subspace: frequency_std_hz over the orders, n_stable_orders, mpc;
  mean: frequency_std_hz over the records, n_tests; peaks: coherence), true_label (the
  paired true mode's label, "" when spurious);
- ``shapes``: record x identified mode x channel: mode, channel, value (real shape);
- ``stability``: record x pole of the stability sweep: order, frequency_hz, damping_ratio,
  mac_prev, mpc, physical, stable;
- ``peaks``: record x candidate peak: frequency_hz, channel, magnitude, coherence,
  phase_change_deg, damping_ratio, accepted, reason;
- ``frf``: record x channel x frequency line up to f_max: channel, frequency_hz, magnitude
  (|H1|), phase_deg, coherence; channel ``indicator`` is sum_k |H1_k| over every output
  channel (magnitude only). The table is for drawing, not for computing: values are
  rounded to 6 significant digits, and long spectra are thinned (:func:`frf_lines`: the
  peaks at full resolution, min-max decimation elsewhere).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pandas as pd

from framework.core.errors import InputError
from framework.identification.frf import FRF
from framework.identification.stability import SelectedModes

INDICATOR = "indicator"


def _value(v):
    """A JSON-able scalar: numpy scalars as Python numbers, NaN as None."""
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, float) and math.isnan(v):
        return None
    return v


def _int_or_none(v):
    v = _value(v)
    return None if v is None else int(v)


def _records(df: pd.DataFrame, columns: Sequence[str]) -> list[dict]:
    return [{c: _value(row[c]) for c in columns} for row in df.to_dict("records")]


def mode_rows(record: str, comparison: pd.DataFrame, deck_energy: np.ndarray | None = None) -> list[dict]:
    """Rows of ``modes`` from :func:`framework.identification.pipeline.compare_to_truth`."""
    rows = []
    for i, row in enumerate(comparison.to_dict("records")):
        out = {"record": record, "mode": _int_or_none(row["mode"]), "mode_label": row["label"]}
        for c in ("f_true_hz", "f_identified_hz", "f_error_pct", "zeta_true", "zeta_identified", "zeta_error_pct",
                  "mac_to_true", "stable"):
            out[c] = _value(row[c])
        out["identified_mode"] = _int_or_none(row["identified_mode"])
        if deck_energy is not None:
            out["deck_energy"] = float(deck_energy[i]) if i < len(deck_energy) else None
        rows.append(out)
    return rows


def identified_rows(record: str, selected: SelectedModes, comparison: pd.DataFrame) -> list[dict]:
    """Rows of ``identified``: the selection table plus the paired true mode's label."""
    paired = {int(j): label for j, label in zip(comparison["identified_mode"], comparison["label"])
              if not pd.isna(j) and label != "spurious"}
    table = selected.table
    columns = [c for c in table.columns if c != "mode"]
    rows = []
    for k, row in enumerate(_records(table, columns), start=1):
        rows.append({"record": record, "mode": k, **row, "true_label": paired.get(k, "")})
    return rows


def shape_rows(record: str, selected: SelectedModes) -> list[dict]:
    return [
        {"record": record, "mode": j + 1, "channel": channel, "value": float(selected.shapes[i, j])}
        for j in range(selected.shapes.shape[1])
        for i, channel in enumerate(selected.output_labels)
    ]


def stability_rows(record: str, stability: pd.DataFrame) -> list[dict]:
    columns = ["order", "frequency_hz", "damping_ratio", "mac_prev", "mpc", "physical", "stable"]
    return [{"record": record, **row} for row in _records(stability, columns)]


def peak_rows(record: str, peaks: pd.DataFrame) -> list[dict]:
    columns = ["frequency_hz", "channel", "magnitude", "coherence", "phase_change_deg", "damping_ratio", "accepted",
               "reason"]
    return [{"record": record, **row} for row in _records(peaks, columns)]


def _round(x: np.ndarray) -> list[float]:
    return [float(f"{v:.6g}") for v in np.asarray(x, float)]


#: relative half-width of the band around a candidate peak where every FRF line is stored
PEAK_WINDOW = 0.02


def frf_lines(frequency_hz: np.ndarray, indicator: np.ndarray, f_max_hz: float, peaks_hz: Sequence[float],
              max_lines: int) -> np.ndarray:
    """Indices of the FRF lines stored: all lines up to ``f_max_hz`` if there are at most
    ``max_lines``; else, min-max decimation of the indicator (the highest and the lowest line
    of each of max_lines / 2 bins, so no resonance or trough is lost from the drawing), the
    first and last line, and every line within +-PEAK_WINDOW f_p of each candidate peak f_p
    (the peaks at full resolution)."""
    lines = np.flatnonzero(frequency_hz <= f_max_hz)
    if lines.size <= max_lines:
        return lines
    keep = {int(lines[0]), int(lines[-1])}
    for chunk in np.array_split(lines, max(1, max_lines // 2)):
        keep.add(int(chunk[np.argmax(indicator[chunk])]))
        keep.add(int(chunk[np.argmin(indicator[chunk])]))
    for fp in peaks_hz:
        keep.update(int(k) for k in lines[np.abs(frequency_hz[lines] - fp) <= PEAK_WINDOW * fp])
    return np.array(sorted(keep))


def frf_rows(record: str, frf: FRF, channels: Sequence[str], f_max_hz: float, peaks_hz: Sequence[float] = (),
             max_lines: int = 300, input_index: int = 0) -> list[dict]:
    """Rows of ``frf``: the indicator and the FRF of ``channels`` at the lines of :func:`frf_lines`."""
    h_all = frf.h[:, :, input_index]
    indicator = np.abs(h_all).sum(axis=1)
    keep = frf_lines(frf.frequency_hz, indicator, f_max_hz, peaks_hz, max_lines)
    f = _round(frf.frequency_hz[keep])
    h = h_all[keep]
    rows = [{"record": record, "channel": INDICATOR, "frequency_hz": fk, "magnitude": m}
            for fk, m in zip(f, _round(indicator[keep]))]
    for channel in channels:
        k = frf.output_labels.index(channel)
        rows += [
            {"record": record, "channel": channel, "frequency_hz": fk, "magnitude": m, "phase_deg": p, "coherence": c}
            for fk, m, p, c in zip(f, _round(np.abs(h[:, k])), _round(np.degrees(np.angle(h[:, k]))),
                                   _round(frf.coherence[keep, k]))
        ]
    return rows


def frf_channels(choice: str | Sequence[str], frf: FRF, peaks: pd.DataFrame) -> list[str]:
    """The channels whose FRF is stored: "all", "peaks" (the strongest channel at each
    candidate peak, in channel order) or the given names."""
    if choice == "all":
        return list(frf.output_labels)
    if choice == "peaks":
        at_peaks = set(peaks["channel"])
        return [c for c in frf.output_labels if c in at_peaks]
    unknown = [c for c in choice if c not in frf.output_labels]
    if unknown:
        raise InputError(f"frf_channels: {unknown} are not output channels {list(frf.output_labels)}")
    return list(choice)
