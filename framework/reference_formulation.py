"""Reference formulation of the SMU benchmarks (eigenvalue difference + MAC), selectable as
``objective: {formulation: reference, options: {matching: order, weights: std}}``.

For measured mode i paired with analytical mode j(i):

    r_lambda,i = sqrt(alpha w_f,i) w_lambda,i (lambda_e,i - lambda_a,j) / lambda_e,i
    r_psi,i    = sqrt(beta w_s,i)  w_psi,i (1 - sqrt(MAC_ij)) / sqrt(MAC_ij)
    Pi         = sum r_lambda,i^2 + sum r_psi,i^2

with lambda = (2 pi f)^2 and, for ``weights: std`` (default),
w_lambda,i = lambda_e,i / std_lambda,i (std_lambda = 2 lambda std_f / f from the measured
frequency standard deviation) and w_psi,i = 1 / || std_psi(:, i) without entry q_i ||,
q_i the reference entry of measured shape i (the entry equal to 1, else the largest
magnitude) at which measured and simulated shapes are normalized to 1. MAC does not
depend on that normalization, so q_i only decides which entry leaves the weight. Without
standard deviations (or ``weights: unit``) the weights are 1. w_f, w_s are the measured
modes' own weights (default 1), alpha and beta those of the objective spec.

Options (``ObjectiveSpec.options``):
- ``matching``: "order" (forced: measured mode i <-> analytical mode i, every pair
  counts, as in the reference) or "mac" (one-to-one highest MAC above
  ``mac_threshold``, within ``frequency_window``); an unmatched mode adds
  ``unmatched_penalty`` to Pi (choose it of the size of the weighted residuals).
- ``weights``: "std" or "unit".
"""

from __future__ import annotations

import math

import numpy as np

from framework.correlation import pair_modes
from framework.errors import InputError
from framework.measurements import MeasuredModes
from framework.models.base import ModalResult
from framework.objectives import (
    Formulation,
    ModeCorrelation,
    ObjectiveSpec,
    spec_n_residuals,
    spec_split,
    use_shape_term,
)

MATCHING = ("order", "mac")
WEIGHTS = ("std", "unit")
KNOWN_OPTIONS = {"matching", "weights"}


def check_options(options: dict) -> None:
    """Reject unknown option keys and values (called when the ObjectiveSpec is built)."""
    unknown = sorted(set(options) - KNOWN_OPTIONS)
    if unknown:
        raise ValueError(f"unknown key(s) {unknown} for formulation 'reference'; known: {sorted(KNOWN_OPTIONS)}")
    if options.get("matching", "order") not in MATCHING:
        raise ValueError(f"matching must be one of {list(MATCHING)}, got {options['matching']!r}")
    if options.get("weights", "std") not in WEIGHTS:
        raise ValueError(f"weights must be one of {list(WEIGHTS)}, got {options['weights']!r}")


def _options(spec: ObjectiveSpec) -> tuple[str, str]:
    opts = spec.options or {}
    return opts.get("matching", "order"), opts.get("weights", "std")


def eigenvalue_rad2_per_s2(f_hz: np.ndarray) -> np.ndarray:
    """lambda = (2 pi f)^2."""
    return (2.0 * math.pi * np.asarray(f_hz, float)) ** 2


def reference_entries(shapes: np.ndarray) -> np.ndarray:
    """q_i per column: the first entry exactly equal to 1, else the largest magnitude."""
    shapes = np.asarray(shapes, float)
    q = np.argmax(np.abs(shapes), axis=0)
    for i in range(shapes.shape[1]):
        ones = np.flatnonzero(shapes[:, i] == 1.0)
        if ones.size:
            q[i] = ones[0]
    return q


def normalize_at(shapes: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Scale column i so that entry q_i equals 1 (columns with a zero there are left as they are)."""
    shapes = np.asarray(shapes, float)
    ref = shapes[q, np.arange(shapes.shape[1])]
    scale = np.where(ref != 0.0, ref, 1.0)
    return shapes / scale


def eigenvalue_weights(measured: MeasuredModes, weights: str) -> np.ndarray:
    """w_lambda,i = lambda_e,i / std_lambda,i, std_lambda = 2 lambda std_f / f (or 1)."""
    if weights == "unit" or measured.frequency_std_hz is None:
        return np.ones(measured.n_modes)
    f = measured.frequencies_hz
    lam = eigenvalue_rad2_per_s2(f)
    std_lam = 2.0 * lam * measured.frequency_std_hz / f
    if np.any(std_lam <= 0):
        raise InputError(
            f"{measured.source}: frequency_std_hz must be > 0 for weights 'std', "
            f"got {measured.frequency_std_hz.tolist()}"
        )
    return lam / std_lam


def shape_weights(measured: MeasuredModes, weights: str) -> np.ndarray:
    """w_psi,i = 1 / || std_psi(:, i) without entry q_i || (or 1)."""
    if weights == "unit" or measured.shape_std is None or measured.shapes is None:
        return np.ones(measured.n_modes)
    q = reference_entries(measured.shapes)
    out = np.empty(measured.n_modes)
    for i in range(measured.n_modes):
        norm = np.linalg.norm(np.delete(measured.shape_std[:, i], q[i]))
        if norm <= 0:
            raise InputError(f"{measured.source}: shape_std of mode {i + 1} is zero; use weights 'unit'")
        out[i] = 1.0 / norm
    return out


def reference_residuals(result: ModalResult, measured: MeasuredModes, spec: ObjectiveSpec):
    """Residual vector [r_lambda (m), r_psi (m)] and the correlation it used."""
    matching, weights = _options(spec)
    shapes = use_shape_term(measured, spec)
    phi_a = result.at(measured.dofs) if measured.has_shapes else None
    phi_e = measured.shapes
    pairing = pair_modes(
        result.frequencies_hz,
        measured.frequencies_hz,
        phi_a,
        phi_e,
        mac_threshold=0.0 if matching == "order" else spec.mac_threshold,
        frequency_window=None if matching == "order" else spec.frequency_window,
        method=matching if phi_a is not None else ("order" if matching == "order" else "frequency"),
    )
    idx, matched = pairing.analytical_index, pairing.matched
    fe = measured.frequencies_hz
    fa = np.full(fe.size, np.nan)
    fa[idx >= 0] = result.frequencies_hz[idx[idx >= 0]]
    lam_e, lam_a = eigenvalue_rad2_per_s2(fe), eigenvalue_rad2_per_s2(fa)
    unmatched = np.sqrt(spec.unmatched_penalty / (2.0 if shapes else 1.0))
    w_lam = eigenvalue_weights(measured, weights) * np.sqrt(spec.alpha * measured.w_frequency)
    r_lam = np.where(matched, w_lam * np.nan_to_num((lam_e - lam_a) / lam_e), unmatched)
    mac = pairing.mac if phi_a is not None else np.full(fe.size, np.nan)
    corr = ModeCorrelation(idx, fe, fa, (fa - fe) / fe, mac, matched)
    if not shapes:
        return r_lam, corr
    sq = np.sqrt(np.clip(np.nan_to_num(mac), 1e-12, 1.0))
    w_psi = shape_weights(measured, weights) * np.sqrt(spec.beta * measured.w_shape)
    r_psi = np.where(matched, w_psi * (1.0 - sq) / sq, unmatched)
    return np.concatenate([r_lam, r_psi]), corr


FORMULATION = Formulation(
    reference_residuals,
    spec_n_residuals,  # same layout as the SPEC residuals: [eigenvalue terms, shape terms]
    spec_split,
    objective_names=("Pi_lambda", "Pi_MAC"),
    check_options=check_options,
)
