"""The SPEC formulation (SPEC 3): relative frequency errors and a MAC term, as a residual vector.

For measured modes i = 1..m paired with analytical modes (:mod:`framework.updating.pairing`):

    eps_i = (f_a,i - f_e,i) / f_e,i                      relative frequency error
    r_f,i = sqrt(alpha w_f,i) eps_i
    r_s,i = sqrt(beta w_s,i) (1 - sqrt(MAC_i)) / sqrt(MAC_i)
    Pi    = sum r_f,i^2 + sum r_s,i^2 = alpha Pi_f + beta Pi_MAC

An unmatched measured mode (no analytical partner with MAC >= threshold) has its two residuals
set to sqrt(unmatched_penalty / 2) each, so it adds ``unmatched_penalty`` to Pi.

Exact Jacobian (:func:`spec_jacobian`, pairing held fixed): d eps_i = df_a / f_e,i with
df = dlambda / (8 pi^2 f); d[(1 - sqrt MAC)/sqrt MAC] = -dMAC / (2 MAC^1.5) with the MAC
derivative of :func:`framework.updating.pairing.mac_derivative`.

Residuals and data noise (:func:`spec_residual_std`): the frequency rows are exactly Gaussian
in the frequency noise, s_i = sqrt(alpha w_f,i) sigma_f,i / f_e,i; the MAC rows are not
Gaussian in shape noise and are taken as Gaussian with s = sqrt(beta w_s,i) (n_dof - 1)
s_rel^2 / 2, the size of the MAC term that shape noise of relative std s_rel (root mean square
over the mode's components, relative to its peak) gives (an assumption, named in
``noise_assumed``).
"""

from __future__ import annotations

import numpy as np

from framework.core.errors import InputError
from framework.measured.modes import MeasuredModes
from framework.models.base import ModalResult
from framework.updating.formulations.base import Formulation, ResidualStd
from framework.updating.pairing import (
    ModeCorrelation,
    ModeCorrelations,
    correlate,
    frequency_derivative,
    mac_derivative,
    measured_rows,
    pair_population,
    shape_term_derivative,
    use_shape_term,
)


def spec_residuals(result: ModalResult, measured: MeasuredModes, spec):
    """Residual vector [r_f (m), r_s (m)] of SPEC 3 and the correlation it used."""
    corr = correlate(result, measured, spec)
    m = measured.n_modes
    unmatched = np.sqrt(spec.unmatched_penalty / (2.0 if use_shape_term(measured, spec) else 1.0))
    r_f = np.where(
        corr.matched,
        np.sqrt(spec.alpha * measured.w_frequency) * np.nan_to_num(corr.frequency_error),
        unmatched,
    )
    if not use_shape_term(measured, spec):
        return r_f, corr
    mac = np.clip(np.nan_to_num(corr.mac), 1e-12, 1.0)
    sq = np.sqrt(mac)
    r_s = np.where(corr.matched, np.sqrt(spec.beta * measured.w_shape) * (1.0 - sq) / sq, unmatched)
    assert r_s.size == m
    return np.concatenate([r_f, r_s]), corr


def spec_residuals_batch(freqs: np.ndarray, shapes: np.ndarray, measured: MeasuredModes, spec):
    """Vectorized :func:`spec_residuals` for a population with equal mode counts.

    freqs (n, m_a), shapes (n, n_dof, m_a) already restricted to the measured DOFs (or None).
    Returns residuals (n, r) and the points' correlations (:class:`ModeCorrelations`), or
    None if the population is too large to pair by enumeration (the caller then uses the
    per-point path).
    """
    use_shapes = spec.use_shapes and measured.has_shapes
    paired = pair_population(freqs, shapes, measured, spec, use_shapes)
    if paired is None:
        return None
    idx, mac, matched = paired
    fe = measured.frequencies_hz
    n = freqs.shape[0]
    fa = np.where(idx >= 0, freqs[np.arange(n)[:, None], np.maximum(idx, 0)], np.nan)
    eps = (fa - fe) / fe
    shape_term = use_shape_term(measured, spec)
    unmatched = np.sqrt(spec.unmatched_penalty / (2.0 if shape_term else 1.0))
    r_f = np.where(matched, np.sqrt(spec.alpha * measured.w_frequency) * np.nan_to_num(eps), unmatched)
    if shape_term:
        sq = np.sqrt(np.clip(np.nan_to_num(mac), 1e-12, 1.0))
        r_s = np.where(matched, np.sqrt(spec.beta * measured.w_shape) * (1.0 - sq) / sq, unmatched)
        r = np.concatenate([r_f, r_s], axis=1)
    else:
        r = r_f
    mac_out = mac if use_shapes else np.full_like(eps, np.nan)
    return r, ModeCorrelations(idx, fe, fa, eps, mac_out, matched)


def spec_jacobian(result: ModalResult, derivatives, corr: ModeCorrelation, measured: MeasuredModes,
                  spec) -> np.ndarray:
    """d r / d theta (r, k) of :func:`spec_residuals` at a point with the pairing ``corr`` held fixed
    (unmatched modes: zero rows). dr_f,i = sqrt(alpha w_f,i) df_a / f_e,i;
    dr_s,i = sqrt(beta w_s,i) d[(1 - sqrt MAC_i) / sqrt MAC_i]."""
    m = measured.n_modes
    shape_term = use_shape_term(measured, spec)
    J = np.zeros((spec_n_residuals(measured, spec), len(derivatives.parameters)))
    rows = measured_rows(result, measured) if shape_term else None
    for i in np.flatnonzero(corr.matched):
        a = int(corr.analytical_index[i])
        pos = derivatives.position(a)
        df = frequency_derivative(result.frequencies_hz[a], derivatives.dlambda[pos])
        J[i] = np.sqrt(spec.alpha * measured.w_frequency[i]) * df / measured.frequencies_hz[i]
        if shape_term:
            phi_a = result.shapes[rows, a]
            dmac = mac_derivative(measured.shapes[:, i], phi_a, derivatives.dphi[rows, pos, :])
            mac = float(np.clip(corr.mac[i], 1e-12, 1.0))
            J[m + i] = np.sqrt(spec.beta * measured.w_shape[i]) * shape_term_derivative(mac, dmac)
    return J


def spec_n_residuals(measured: MeasuredModes, spec) -> int:
    return measured.n_modes * (2 if use_shape_term(measured, spec) else 1)


def spec_split(residuals: np.ndarray, measured: MeasuredModes, spec) -> np.ndarray:
    """Objective vector [Pi_f, Pi_MAC] from the modal residuals (..., r)."""
    m = measured.n_modes
    r2 = np.asarray(residuals) ** 2
    pi_f = r2[..., :m].sum(-1)
    pi_s = r2[..., m : 2 * m].sum(-1) if use_shape_term(measured, spec) else np.zeros_like(pi_f)
    return np.stack([pi_f, pi_s], axis=-1)




def spec_residual_std(measured: MeasuredModes, spec, noise) -> ResidualStd:
    """Standard deviations of the SPEC residuals given the data's noise (module docstring)."""
    f_std = np.asarray(noise.frequency_std_hz, float)
    scales = np.sqrt(spec.alpha * measured.w_frequency) * f_std / measured.frequencies_hz
    shape_rows = use_shape_term(measured, spec)
    assumption = ""
    if shape_rows:
        n_dof = len(measured.dofs)
        peak = np.max(np.abs(measured.shapes), axis=0)
        s_rel = np.sqrt(np.mean((np.asarray(noise.shape_std, float) / peak) ** 2, axis=0))
        s_mac = np.sqrt(spec.beta * measured.w_shape) * max(n_dof - 1, 1) * s_rel**2 / 2.0
        scales = np.r_[scales, s_mac]
        data_std = np.r_[f_std, s_mac]
        assumption = "MAC residual Gaussian with std (n_dof-1) s^2/2"
    else:
        data_std = f_std
    if np.any(scales <= 0):
        raise InputError("likelihood: a residual has zero weight (alpha, beta or a mode weight is 0); "
                         "its standard deviation would be 0")
    return ResidualStd(scales, data_std, scales.size, assumption, shape_rows)


SPEC = Formulation(
    "spec",
    spec_residuals,
    spec_n_residuals,
    spec_split,
    batch_residuals=spec_residuals_batch,
    jacobian=spec_jacobian,
    residual_std=spec_residual_std,
)
