"""The Gaussian formulation: residuals whitened by the data's noise, so that Pi = chi2 and the
least-squares minimum is the maximum-likelihood estimate.

The modes are paired as every formulation pairs them (:mod:`framework.updating.pairing`: highest
MAC, one-to-one; nearest frequency without shapes); the whitening, with a least-squares scale
per mode shape and the charge of an unmatched mode, is :mod:`framework.inference.gaussian`,
one definition for a point and for a population (``batch_residuals``, used by
``UpdatingProblem.evaluate`` for two or more points).

Standard deviations: the data's (``frequency_std_hz``, ``shape_std``), else the assumed
defaults of :mod:`framework.inference.noise` (1 % of f, 5 % of the mode's largest shape
component): the formulation runs with and without standard deviations in the data, and the
likelihood (:func:`framework.inference.likelihood.noise_model`) reports which were assumed
(``noise_assumed``, ``noise_*_source``). A workflow that assumes other levels fixes them in the
data first (:func:`framework.inference.noise.with_stds`, as the diagnosis does with its
settings). Given other data noise than the whitening's (e.g. the ``posterior`` kind's ``noise``
levels), ``residual_std`` gives the ratio of the two, so the likelihood uses the noise it is
given.

Option (``objective.options``): ``unmatched_window`` (default 0.1), the relative frequency
distance an unmatched mode is charged. The objective vector is [chi2_frequency, chi2_shape].
"""

from __future__ import annotations

import numpy as np

from framework.core.errors import InputError
from framework.inference import gaussian as whitening
from framework.inference.noise import DEFAULT_SHAPE_STD_REL, data_noise
from framework.measured.modes import MeasuredModes
from framework.models.base import ModalResult
from framework.updating.formulations.base import Formulation, ResidualStd
from framework.updating.pairing import ModeCorrelations, correlate, pair_population

DEFAULT_UNMATCHED_WINDOW = whitening.DEFAULT_UNMATCHED_WINDOW


def uses_shapes(measured: MeasuredModes, spec) -> bool:
    return bool(spec.use_shapes and measured.has_shapes)


def whitening_noise(measured: MeasuredModes, spec):
    """The standard deviations the residuals are whitened with: the data's, else the defaults."""
    return data_noise(measured, use_shapes=uses_shapes(measured, spec))


def _unmatched(measured: MeasuredModes, spec, noise) -> np.ndarray:
    window = float(spec.options.get("unmatched_window", DEFAULT_UNMATCHED_WINDOW))
    shapes = uses_shapes(measured, spec)
    return whitening.unmatched_chi2(measured.frequencies_hz, noise.frequency_std_hz, window,
                                    measured.shapes if shapes else None, noise.shape_std, spec.mac_threshold)


def gaussian_residuals(result: ModalResult, measured: MeasuredModes, spec):
    """Whitened residual vector [r_f (m), r_s (m * n_dof)] of one point and the correlation it used."""
    corr = correlate(result, measured, spec)
    noise = whitening_noise(measured, spec)
    shapes = uses_shapes(measured, spec)
    a = None
    if shapes:
        a = result.at(measured.dofs)[:, np.maximum(corr.analytical_index, 0)][None, :, :]
    r = whitening.whitened_residuals(corr.f_model_hz[None, :], corr.matched[None, :], measured.frequencies_hz,
                                     noise.frequency_std_hz, _unmatched(measured, spec, noise), a,
                                     measured.shapes if shapes else None, noise.shape_std)
    return r[0], corr


def gaussian_residuals_batch(freqs: np.ndarray, shapes: np.ndarray | None, measured: MeasuredModes, spec):
    """Whitened residuals (n, r) of a population (freqs (n, m_a), shapes (n, n_dof, m_a) at the
    measured DOFs) and its correlations, or None when it is too large to pair by enumeration."""
    use_shapes = uses_shapes(measured, spec)
    paired = pair_population(freqs, shapes, measured, spec, use_shapes)
    if paired is None:
        return None
    idx, mac, matched = paired
    n = len(freqs)
    fe = measured.frequencies_hz
    fa = np.where(idx >= 0, freqs[np.arange(n)[:, None], np.maximum(idx, 0)], np.nan)
    noise = whitening_noise(measured, spec)
    a = np.take_along_axis(shapes, np.maximum(idx, 0)[:, None, :], axis=2) if use_shapes else None
    r = whitening.whitened_residuals(fa, matched, fe, noise.frequency_std_hz, _unmatched(measured, spec, noise), a,
                                     measured.shapes if use_shapes else None, noise.shape_std)
    mac_out = mac if use_shapes else np.full(fa.shape, np.nan)
    return r, ModeCorrelations(idx, fe, fa, (fa - fe) / fe, mac_out, matched)


def n_residuals(measured: MeasuredModes, spec) -> int:
    return whitening.n_residuals(measured.n_modes, len(measured.dofs), uses_shapes(measured, spec))


def n_data(measured: MeasuredModes, spec) -> int:
    """Independent data: m frequencies + m (n_dof - 1) shape components."""
    return whitening.n_data(measured.n_modes, len(measured.dofs), uses_shapes(measured, spec))


def split_chi2(residuals: np.ndarray, measured: MeasuredModes, spec) -> np.ndarray:
    """[chi2_frequency, chi2_shape] from residual rows (..., r)."""
    return whitening.split_chi2(residuals, measured.n_modes)


def per_mode_chi2(residuals: np.ndarray, measured: MeasuredModes, spec) -> tuple[np.ndarray, np.ndarray]:
    """chi2 per measured mode: (frequency part (m,), shape part (m,))."""
    return whitening.per_mode_chi2(residuals, measured.n_modes, len(measured.dofs), uses_shapes(measured, spec))


def gaussian_residual_std(measured: MeasuredModes, spec, noise) -> ResidualStd:
    """Residual i has standard deviation sigma_i / w_i (sigma: the given data noise, w: the
    whitening's): 1 when they are the same."""
    w = whitening_noise(measured, spec)
    scales, data_std = [noise.frequency_std_hz / w.frequency_std_hz], [np.asarray(noise.frequency_std_hz, float)]
    shapes = uses_shapes(measured, spec)
    if shapes:
        scales.append((noise.shape_std / w.shape_std).T.ravel())
        data_std.append(np.asarray(noise.shape_std, float).T.ravel())
    return ResidualStd(np.concatenate(scales), np.concatenate(data_std), n_data(measured, spec), "", shapes)


def check_data(measured: MeasuredModes, spec) -> None:
    """The standard deviations given in the data must be > 0 (each whitens a residual)."""
    whitening_noise(measured, spec)  # a zero frequency std is an InputError there
    if uses_shapes(measured, spec) and measured.shape_std is not None:
        zero = np.argwhere(measured.shape_std <= 0)
        if zero.size:
            d, j = zero[0]
            raise InputError(f"{measured.source}: shape_std of mode {j + 1} at DOF {measured.dofs[d]!r} is 0; the "
                             "gaussian formulation divides by it (give it, or leave shape_std out to assume "
                             f"{100 * DEFAULT_SHAPE_STD_REL:g} % of the peak)")


def check_options(options: dict) -> None:
    """The Gaussian formulation reads one option, ``unmatched_window`` (a number > 0)."""
    unknown = sorted(set(options) - {"unmatched_window"})
    if unknown:
        raise ValueError(f"unknown key(s) {unknown} for formulation 'gaussian'; known: ['unmatched_window']")
    window = options.get("unmatched_window", DEFAULT_UNMATCHED_WINDOW)
    if isinstance(window, bool) or not isinstance(window, (int, float)) or not 0 < window < float("inf"):
        raise ValueError(f"unmatched_window must be a finite number > 0, got {window!r}")


GAUSSIAN = Formulation(
    "gaussian",
    gaussian_residuals,
    n_residuals,
    split_chi2,
    objective_names=("chi2_frequency", "chi2_shape"),
    batch_residuals=gaussian_residuals_batch,
    check_options=check_options,
    residual_std=gaussian_residual_std,
    check_data=check_data,
    uses_weights=False,
)
