"""Excitation signals of the simulated tests: sine sweep, jumping, ambient noise.

All return (n,) arrays sampled at ``sampling_hz``; amplitudes are in the input's unit
(N for a shaker force, m/s^2 for a table acceleration).
"""

from __future__ import annotations

import numpy as np
import scipy.signal

from framework.core.errors import InputError


def _n_samples(duration_s: float, sampling_hz: float) -> int:
    if duration_s <= 0 or sampling_hz <= 0:
        raise InputError(f"duration_s and sampling_hz must be > 0, got {duration_s!r}, {sampling_hz!r}")
    return int(round(duration_s * sampling_hz))


def sine_sweep(
    duration_s: float,
    sampling_hz: float,
    f_start_hz: float,
    f_end_hz: float,
    amplitude: float = 1.0,
    taper_s: float = 1.0,
) -> np.ndarray:
    """Linear sine sweep a sin(2 pi (f0 t + (f1 - f0) t^2 / (2 T))) (scipy.signal.chirp) with
    cosine ramps of ``taper_s`` at both ends to avoid a step at the start."""
    if not 0 <= f_start_hz < f_end_hz < sampling_hz / 2:
        raise InputError(
            f"sine_sweep: need 0 <= f_start_hz < f_end_hz < Nyquist {sampling_hz / 2}, got {f_start_hz!r}, {f_end_hz!r}"
        )
    n = _n_samples(duration_s, sampling_hz)
    t = np.arange(n) / sampling_hz
    x = amplitude * scipy.signal.chirp(t, f_start_hz, duration_s, f_end_hz, method="linear", phi=-90)
    nt = min(int(taper_s * sampling_hz), n // 2)
    if nt > 0:
        ramp = 0.5 * (1 - np.cos(np.pi * np.arange(nt) / nt))
        x[:nt] *= ramp
        x[n - nt :] *= ramp[::-1]
    return x


def jumping(
    duration_s: float,
    sampling_hz: float,
    rng: np.random.Generator,
    rate_hz: tuple[float, float] = (1.5, 3.0),
    contact_s: float = 0.25,
    peak: float = 2000.0,
    ambient_ratio: float = 0.05,
) -> np.ndarray:
    """Jumping load: half-sine contact pulses of random height at random intervals
    (jump rate uniform in ``rate_hz``), plus white ambient noise of ``ambient_ratio`` x peak.

    The random timing spreads the energy over a broad band, as output-only methods assume.
    """
    n = _n_samples(duration_s, sampling_hz)
    x = ambient_ratio * peak * rng.standard_normal(n)
    nc = max(2, int(contact_s * sampling_hz))
    pulse = np.sin(np.pi * np.arange(nc) / nc)
    t = rng.uniform(0, 1 / rate_hz[0])
    while True:
        k = int(t * sampling_hz)
        if k + nc >= n:
            break
        x[k : k + nc] += peak * rng.uniform(0.5, 1.0) * pulse
        t += 1.0 / rng.uniform(*rate_hz)
    return x
