"""Pairing of a model's modes with the measured ones, the correlation it gives (frequency error,
MAC) for one point or a population, and the derivatives of paired quantities (frequency,
MAC) used by the formulations' exact Jacobians.

Pairing follows the objective's settings (``spec``: ``pairing``, ``mac_threshold``,
``frequency_window``, ``use_shapes``; taken duck-typed, any object with those attributes):
highest MAC one-to-one when shapes are used, else by order or by frequency. A measured mode
without a partner (MAC below the threshold, outside the window) is unmatched and never paired
silently.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from framework.core.correlation import pair_modes
from framework.measured.modes import MeasuredModes
from framework.models.base import ModalResult


@dataclass(frozen=True)
class ModeCorrelation:
    """Per measured mode: paired analytical index (-1 unmatched), frequencies, eps, MAC."""

    analytical_index: np.ndarray
    f_measured_hz: np.ndarray
    f_model_hz: np.ndarray
    frequency_error: np.ndarray
    mac: np.ndarray
    matched: np.ndarray


class ModeCorrelations(Sequence):
    """The :class:`ModeCorrelation` of every point of a population, kept as arrays (n, m).

    An item is built only when asked (no per-point objects on the evaluation path);
    ``present[i]`` False (a failed point) gives None.
    """

    def __init__(self, analytical_index, f_measured_hz, f_model_hz, frequency_error, mac, matched, present=None):
        self.analytical_index = analytical_index
        self.f_measured_hz = f_measured_hz
        self.f_model_hz = f_model_hz
        self.frequency_error = frequency_error
        self.mac = mac
        self.matched = matched
        self.present = np.ones(len(f_model_hz), dtype=bool) if present is None else present

    def __len__(self) -> int:
        return len(self.f_model_hz)

    def __getitem__(self, i):
        if isinstance(i, slice):
            return [self[j] for j in range(*i.indices(len(self)))]
        if not self.present[i]:
            return None
        return ModeCorrelation(self.analytical_index[i], self.f_measured_hz, self.f_model_hz[i],
                               self.frequency_error[i], self.mac[i], self.matched[i])

    def set(self, i: int, corr: ModeCorrelation) -> None:
        """Put point i's correlation (computed on its own) into the arrays."""
        self.analytical_index[i], self.f_model_hz[i] = corr.analytical_index, corr.f_model_hz
        self.frequency_error[i], self.mac[i], self.matched[i] = corr.frequency_error, corr.mac, corr.matched
        self.present[i] = True

    def where(self, present: np.ndarray) -> ModeCorrelations:
        """The same correlations with only the points ``present`` (n,) kept."""
        return ModeCorrelations(self.analytical_index, self.f_measured_hz, self.f_model_hz, self.frequency_error,
                                self.mac, self.matched, self.present & present)


def correlation_table(corr: ModeCorrelation, measured: MeasuredModes):
    """One row per measured mode: mode, label, f_measured_hz, f_model_hz, error_pct, mac, matched."""
    import pandas as pd

    return pd.DataFrame(
        {
            "mode": np.arange(1, measured.n_modes + 1),
            "label": list(measured.labels),
            "f_measured_hz": corr.f_measured_hz,
            "f_model_hz": corr.f_model_hz,
            "error_pct": 100.0 * corr.frequency_error,
            "mac": corr.mac,
            "matched": corr.matched,
        }
    )


def correlate(result: ModalResult, measured: MeasuredModes, spec) -> ModeCorrelation:
    """Pair measured modes with the model's and compute eps and MAC of every pair."""
    use_shapes = spec.use_shapes and measured.has_shapes
    phi_a = result.at(measured.dofs) if use_shapes else None
    phi_e = measured.shapes if use_shapes else None
    pairing = pair_modes(
        result.frequencies_hz,
        measured.frequencies_hz,
        phi_a,
        phi_e,
        mac_threshold=spec.mac_threshold,
        frequency_window=spec.frequency_window,
        method=spec.pairing if use_shapes else ("order" if spec.pairing == "order" else "frequency"),
    )
    idx = pairing.analytical_index
    fe = measured.frequencies_hz
    fa = np.full(fe.size, np.nan)
    fa[idx >= 0] = result.frequencies_hz[idx[idx >= 0]]
    eps = (fa - fe) / fe
    mac = pairing.mac if use_shapes else np.full(fe.size, np.nan)
    return ModeCorrelation(idx, fe, fa, eps, mac, pairing.matched)


def pair_population(freqs: np.ndarray, shapes: np.ndarray | None, measured: MeasuredModes, spec,
                    use_shapes: bool):
    """Pair a population's modes with the measured ones as the objective does: by MAC (the
    spec's pairing rule) when shapes are used, else by order or frequency. Returns
    ``pair_modes_batch``'s (index, mac, matched) arrays, or None when the population is too
    large to pair by enumeration."""
    from framework.core.correlation import mac_matrix_batch, pair_modes_batch

    mm = mac_matrix_batch(shapes, measured.shapes) if use_shapes else None
    method = spec.pairing if use_shapes else ("order" if spec.pairing == "order" else "frequency")
    return pair_modes_batch(freqs, measured.frequencies_hz, mm, mac_threshold=spec.mac_threshold,
                            frequency_window=spec.frequency_window, method=method)


def measured_rows(result: ModalResult, measured: MeasuredModes) -> np.ndarray:
    """Rows of ``result.shapes`` (and of ModalDerivatives.dphi) at the measured DOFs, in their order."""
    index = {d: i for i, d in enumerate(result.dofs)}
    return np.array([index[d] for d in measured.dofs], dtype=int)


def mac_derivative(phi_e: np.ndarray, phi_a: np.ndarray, dphi_a: np.ndarray) -> np.ndarray:
    """d MAC / d theta (k,) of real shapes phi_e, phi_a (n,) with dphi_a (n, k):

    dMAC = 2 (phi_e' phi_a)(phi_e' dphi_a) / ((phi_e' phi_e)(phi_a' phi_a)) - MAC 2 (phi_a' dphi_a) / (phi_a' phi_a).
    """
    ea, ee, aa = phi_e @ phi_a, phi_e @ phi_e, phi_a @ phi_a
    mac = ea**2 / (ee * aa)
    return 2.0 * ea * (phi_e @ dphi_a) / (ee * aa) - mac * 2.0 * (phi_a @ dphi_a) / aa


def frequency_derivative(f_hz: float, dlambda: np.ndarray) -> np.ndarray:
    """d f / d theta from d lambda / d theta: f = sqrt(lambda) / 2 pi, so df = dlambda / (8 pi^2 f)."""
    return dlambda / (8.0 * np.pi**2 * f_hz)


def shape_term_derivative(mac: float, dmac: np.ndarray) -> np.ndarray:
    """d[(1 - sqrt MAC) / sqrt MAC] = -dMAC / (2 MAC^1.5) (0 where MAC was clipped at 1e-12)."""
    if mac <= 1e-12:
        return np.zeros_like(dmac)
    return -dmac / (2.0 * mac**1.5)


def use_shape_term(measured: MeasuredModes, spec) -> bool:
    return bool(spec.use_shapes and measured.has_shapes and spec.beta > 0)
