"""Frequency response functions by the H1 estimator, coherence and peak picking.

H1(f) = S_yx(f) S_xx(f)^-1 with Welch-averaged auto/cross spectra (scipy.signal.csd),
default 5 segments, 50 % overlap, Hamming window. With one input this is S_xy / S_xx.
Repeated tests are averaged by summing their spectra before the division.
Coherence is the (multiple) coherence gamma^2 = S_yx S_xx^-1 S_xy / S_yy, which for one
input is the ordinary |S_xy|^2 / (S_xx S_yy).
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
import scipy.signal

from framework.core.errors import InputError
from framework.identification.records import VibrationRecord

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class FRF:
    """h: (n_freq, n_out, n_in) complex H1; coherence: (n_freq, n_out) multiple coherence."""

    frequency_hz: np.ndarray
    h: np.ndarray
    coherence: np.ndarray
    output_labels: tuple[str, ...]
    input_labels: tuple[str, ...]
    n_averages: int

    def to_frame(self) -> pd.DataFrame:
        """Tidy table: one row per frequency, output and input."""
        rows = []
        for i, out in enumerate(self.output_labels):
            for j, inp in enumerate(self.input_labels):
                h = self.h[:, i, j]
                rows.append(
                    pd.DataFrame(
                        {
                            "frequency_hz": self.frequency_hz,
                            "output": out,
                            "input": inp,
                            "magnitude": np.abs(h),
                            "phase_deg": np.degrees(np.angle(h)),
                            "coherence": self.coherence[:, i],
                        }
                    )
                )
        return pd.concat(rows, ignore_index=True)


def welch_segment_length(n_samples: int, n_segments: int, overlap: float) -> int:
    """Segment length L giving ``n_segments`` segments with fractional ``overlap``:
    n = L + (K - 1)(1 - overlap) L."""
    if n_segments < 1 or not 0 <= overlap < 1:
        raise InputError(f"n_segments must be >= 1 and overlap in [0, 1), got {n_segments!r}, {overlap!r}")
    return int(n_samples / (1 + (n_segments - 1) * (1 - overlap)))


def h1_frf(
    records: VibrationRecord | Sequence[VibrationRecord],
    n_segments: int = 5,
    overlap: float = 0.5,
    window: str = "hamming",
) -> FRF:
    """H1 FRF and coherence averaged over one or more records with equal channels and fs."""
    recs = [records] if isinstance(records, VibrationRecord) else list(records)
    if not recs:
        raise InputError("h1_frf: no records given")
    first = recs[0]
    if not first.has_inputs:
        raise InputError(f"h1_frf: record {first.name!r} has no input channels (output-only test)")
    for r in recs[1:]:
        if r.output_labels != first.output_labels or r.input_labels != first.input_labels:
            raise InputError(f"h1_frf: record {r.name!r} has channels different from {first.name!r}")
        if abs(r.sampling_hz - first.sampling_hz) > 1e-9 * first.sampling_hz:
            raise InputError(f"h1_frf: record {r.name!r} sampling_hz {r.sampling_hz} != {first.sampling_hz}")
    fs = first.sampling_hz
    nper = welch_segment_length(min(r.n_samples for r in recs), n_segments, overlap)
    nover = int(round(overlap * nper))
    kw = dict(fs=fs, window=window, nperseg=nper, noverlap=nover)
    n_in, n_out = first.inputs.shape[1], first.outputs.shape[1]
    sxx = syx = syy = None
    for r in recs:
        u, y = r.inputs, r.outputs
        f, _ = scipy.signal.welch(u[:, 0], **kw)
        a = np.zeros((f.size, n_in, n_in), complex)
        b = np.zeros((f.size, n_out, n_in), complex)
        c = np.zeros((f.size, n_out))
        for i in range(n_in):
            for j in range(n_in):
                a[:, i, j] = scipy.signal.csd(u[:, i], u[:, j], **kw)[1]
            for k in range(n_out):
                b[:, k, i] = scipy.signal.csd(u[:, i], y[:, k], **kw)[1]  # conj(X_i) Y_k
        for k in range(n_out):
            c[:, k] = scipy.signal.welch(y[:, k], **kw)[1]
        sxx, syx, syy = (a, b, c) if sxx is None else (sxx + a, syx + b, syy + c)
    # H1 = S_yx S_xx^-1 (rows = outputs): solve S_xx^T H^T = S_yx^T per frequency
    eps = 1e-30 * np.max(np.abs(sxx))
    sxx_reg = sxx + eps * np.eye(n_in)
    h = np.swapaxes(np.linalg.solve(np.swapaxes(sxx_reg, 1, 2), np.swapaxes(syx, 1, 2)), 1, 2)
    coh = np.real(np.einsum("fki,fki->fk", h, np.conj(syx))) / np.maximum(syy, 1e-300)
    return FRF(f, h, np.clip(coh, 0.0, 1.0), first.output_labels, first.input_labels, len(recs) * n_segments)


def pick_peaks(
    frf: FRF,
    band_hz: tuple[float, float] | None = None,
    min_coherence: float = 0.8,
    min_phase_change_deg: float = 120.0,
    phase_window: float = 0.05,
    prominence: float = 0.05,
    input_index: int = 0,
) -> pd.DataFrame:
    """Peak picking on the mode indicator sum_k |H_k| (one input column).

    A candidate is a local maximum with relative prominence > ``prominence``; it is
    accepted when the coherence of the output channel with the largest |H| there exceeds
    ``min_coherence`` and the phase of the FRF projected on the peak's operating shape
    psi = H(f_p) / |H(f_p)| (psi^H H(f)) turns by more than ``min_phase_change_deg``
    between f_p - w and f_p + w (a single mode turns it by 2 atan(w / hw): 157 degrees at
    w = 5 hw, 180 far off; neighbouring modes' background lowers it), w = 5 x the
    half-power half-width hw (at least 2.5 lines, at
    most phase_window f_p and 0.4 x the distance to the nearest other peak). The
    frequency is refined by a parabola through log|H| at the three bins around the peak;
    damping by the half-power method, zeta = hw / f_p (NaN when the peak is narrower than
    a line). Returns one row per candidate with the reason of any rejection.
    """
    f = frf.frequency_hz
    h = frf.h[:, :, input_index]
    indicator = np.sum(np.abs(h), axis=1)
    mask = np.ones_like(f, bool) if band_hz is None else (f >= band_hz[0]) & (f <= band_hz[1])
    if not mask.any():
        raise InputError(f"pick_peaks: band_hz {band_hz!r} contains no frequency line")
    ind = np.where(mask, indicator, 0.0)
    peaks, props = scipy.signal.find_peaks(ind, prominence=prominence * ind.max())
    rows = []
    f_peaks = f[peaks]
    for p in peaks:
        ch = int(np.argmax(np.abs(h[p])))
        mag = np.log(np.abs(h[max(p - 1, 0) : p + 2, ch]) + 1e-300)
        fp = f[p]
        if 0 < p < f.size - 1 and mag.size == 3:
            den = mag[0] - 2 * mag[1] + mag[2]
            if den < 0:
                fp = f[p] + 0.5 * (mag[0] - mag[2]) / den * (f[1] - f[0])
        hw = _half_power_half_width(np.abs(h[:, ch]), p, f[1] - f[0])
        others = np.abs(f_peaks[f_peaks != f[p]] - fp)
        cap = min(phase_window * fp, 0.4 * others.min()) if others.size else phase_window * fp
        half = min(max(5.0 * hw, 2.5 * (f[1] - f[0])), cap)
        lo = np.flatnonzero((f >= fp - half) & (f < fp))
        hi = np.flatnonzero((f > fp) & (f <= fp + half))
        dphi = 0.0
        if lo.size and hi.size:
            # phase turned across the resonance: angle of H(f_p + w) conj(H(f_p - w)) (no
            # unwrapping of noisy phase needed)
            # on the FRF projected onto the operating shape at the peak, which weights the
            # channels by the mode and so suppresses neighbouring modes' background
            psi = h[p] / np.linalg.norm(h[p])
            a, b = np.vdot(psi, h[lo[0]]), np.vdot(psi, h[hi[-1]])
            dphi = float(np.degrees(abs(np.angle(b * np.conj(a)))))
        coh = float(frf.coherence[p, ch])
        reasons = []
        if coh < min_coherence:
            reasons.append(f"coherence {coh:.2f} < {min_coherence}")
        if dphi < min_phase_change_deg:
            reasons.append(f"phase change {dphi:.0f} deg < {min_phase_change_deg:.0f}")
        rows.append(
            {
                "frequency_hz": float(fp),
                "channel": frf.output_labels[ch],
                "magnitude": float(np.abs(h[p, ch])),
                "coherence": coh,
                "phase_change_deg": dphi,
                "damping_ratio": hw / fp if hw > 0 else np.nan,
                "accepted": not reasons,
                "reason": "; ".join(reasons),
            }
        )
    table = pd.DataFrame(
        rows,
        columns=[
            "frequency_hz",
            "channel",
            "magnitude",
            "coherence",
            "phase_change_deg",
            "damping_ratio",
            "accepted",
            "reason",
        ],
    )
    log.info("peak picking: %d candidates, %d accepted", len(table), int(table["accepted"].sum()) if rows else 0)
    return table


def _half_power_half_width(mag: np.ndarray, p: int, df: float) -> float:
    """Half of the width where |H| >= |H_p| / sqrt(2), linearly interpolated between lines."""
    level = mag[p] / np.sqrt(2.0)
    i = p
    while i > 0 and mag[i] >= level:
        i -= 1
    j = p
    while j < mag.size - 1 and mag[j] >= level:
        j += 1
    left = i + (level - mag[i]) / (mag[i + 1] - mag[i]) if mag[i + 1] != mag[i] else float(i)
    right = j - (level - mag[j]) / (mag[j - 1] - mag[j]) if mag[j - 1] != mag[j] else float(j)
    return 0.5 * (right - left) * df

