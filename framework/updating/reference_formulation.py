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
- ``shape_term``: "mac" (default, above) or "eigenvector": the SMU eigenvector-difference
  formulation. Per measured mode i, with measured and simulated shapes both normalized to
  1 at the reference entry q_i (psi = phi / phi(q_i)), one residual per other measured DOF d:

      r_psi,i,d = sqrt(beta w_s,i) w_psi,i,d (psi_e,i(d) - psi_a,j(d)),   d != q_i

  With ``weights: unit`` or without shape standard deviations w_psi,i,d = 1 (the SMU
  four-storey example's ones). With ``weights: std`` and shape standard deviations, the
  option ``eigenvector_weights`` chooses (n_dof = number of measured DOFs):

  - "entry" (default): w_psi,i,d = 1 / (n_dof std_psi(d, i)), the weights the SMU footbridge
    example sets up (it divides 1/std by the number of measured DOFs).
  - "smu_as_run": w_psi,i,d = 1 / (n_dof std_psi(i, 1)) for every entry d of mode i: the
    weights the SMU package's objective code actually applies to that (n_dof x m) weight
    matrix (it reads it with one index, psiWeights(i), which in column-major order is the
    i-th entry of its first column), and so the weights of its published footbridge results
    (SteelPedBridg_form2_*: fval 2.8474 at its best x, which this option reproduces to 4e-11,
    where "entry" gives 2.1388). Use it only to compare with those results.

  Until issue 27 "entry" omitted the factor 1 / n_dof (a bug against the SMU formulation it
  claimed to follow); that objective is "entry" with ``beta`` = n_dof^2.
  Residual layout: [r_lambda (m), mode 1's n_dof - 1 shape residuals, mode
  2's, ...]; an unmatched mode sets its n_dof residuals to sqrt(unmatched_penalty / n_dof).
  A simulated shape that is exactly 0 at q_i fails the evaluation ("zero_reference_entry").
  The objective vector stays [Pi_lambda, Pi_MAC], the second being the shape term either way.

Exact Jacobians (:func:`reference_jacobian`, pairing held fixed, unmatched modes zero rows):
dr_lambda,i = -w_lambda,i dlambda_a,j / lambda_e,i; the MAC term as in
:func:`framework.updating.objectives.spec_jacobian`; dr_psi,i,d = -sqrt(beta w_s,i) w_psi,i,d
(dphi_a(d) - psi_a(d) dphi_a(q_i)) / phi_a(q_i).
"""

from __future__ import annotations

import math

import numpy as np

from framework.core.correlation import pair_modes
from framework.core.errors import InputError, ModelEvaluationError
from framework.measured.modes import MeasuredModes
from framework.models.base import ModalResult
from framework.updating.objectives import (
    Formulation,
    ModeCorrelation,
    ObjectiveSpec,
    mac_derivative,
    measured_rows,
    shape_term_derivative,
    spec_n_residuals,
    use_shape_term,
)

MATCHING = ("order", "mac")
WEIGHTS = ("std", "unit")
SHAPE_TERMS = ("mac", "eigenvector")
EIGENVECTOR_WEIGHTS = ("entry", "smu_as_run")
KNOWN_OPTIONS = {"matching", "weights", "shape_term", "eigenvector_weights"}


def check_options(options: dict) -> None:
    """Reject unknown option keys and values (called when the ObjectiveSpec is built)."""
    unknown = sorted(set(options) - KNOWN_OPTIONS)
    if unknown:
        raise ValueError(f"unknown key(s) {unknown} for formulation 'reference'; known: {sorted(KNOWN_OPTIONS)}")
    if options.get("matching", "order") not in MATCHING:
        raise ValueError(f"matching must be one of {list(MATCHING)}, got {options['matching']!r}")
    if options.get("weights", "std") not in WEIGHTS:
        raise ValueError(f"weights must be one of {list(WEIGHTS)}, got {options['weights']!r}")
    if options.get("shape_term", "mac") not in SHAPE_TERMS:
        raise ValueError(f"shape_term must be one of {list(SHAPE_TERMS)}, got {options['shape_term']!r}")
    if options.get("eigenvector_weights", "entry") not in EIGENVECTOR_WEIGHTS:
        raise ValueError(f"eigenvector_weights must be one of {list(EIGENVECTOR_WEIGHTS)}, "
                         f"got {options['eigenvector_weights']!r}")


def _options(spec: ObjectiveSpec) -> tuple[str, str]:
    opts = spec.options or {}
    return opts.get("matching", "order"), opts.get("weights", "std")


def _eigenvector_term(spec: ObjectiveSpec) -> bool:
    return (spec.options or {}).get("shape_term", "mac") == "eigenvector"


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


def entry_weights(measured: MeasuredModes, weights: str, scheme: str = "entry") -> np.ndarray:
    """Eigenvector-term weights w_psi,i,d (n_dof, m) of the module docstring: 1 without
    standard deviations (or ``weights: unit``); else, for ``scheme`` "entry",
    1 / (n_dof std_psi(d, i)), for "smu_as_run", 1 / (n_dof std_psi(i, 1)) down column i.

    The reference entries q_i (std 0 after normalization) are left out of the residuals, so a
    zero standard deviation there is fine; any other zero standard deviation in use is an
    input error."""
    n_dof, m = len(measured.dofs), measured.n_modes
    if weights == "unit" or measured.shape_std is None or measured.shapes is None:
        return np.ones((n_dof, m))
    std = np.array(measured.shape_std, dtype=float)
    if scheme == "smu_as_run":
        if m > n_dof:
            raise InputError(f"{measured.source}: eigenvector_weights 'smu_as_run' needs at most as many modes "
                             f"({m}) as measured DOFs ({n_dof})")
        first = std[:m, 0]  # psiWeights(i), i = 1..m, of the SMU code: column-major entry i of the matrix
        if np.any(first <= 0):
            i = int(np.flatnonzero(first <= 0)[0])
            raise InputError(f"{measured.source}: shape_std of mode 1 at DOF {measured.dofs[i]!r} is zero; "
                             "eigenvector_weights 'smu_as_run' cannot use it")
        return np.broadcast_to(1.0 / (n_dof * first), (n_dof, m)).copy()
    q = reference_entries(measured.shapes)
    std[q, np.arange(m)] = 1.0
    zero = np.argwhere(std <= 0)
    if zero.size:
        d, i = zero[0]
        raise InputError(
            f"{measured.source}: shape_std of mode {i + 1} at DOF {measured.dofs[d]!r} is zero; "
            "use weights 'unit' for the eigenvector term"
        )
    return 1.0 / (n_dof * std)


def _eigenvector_weights(measured: MeasuredModes, spec: ObjectiveSpec) -> np.ndarray:
    """w_psi,i,d sqrt(beta w_s,i) (n_dof, m) for the spec's options."""
    _, weights = _options(spec)
    scheme = (spec.options or {}).get("eigenvector_weights", "entry")
    return entry_weights(measured, weights, scheme) * np.sqrt(spec.beta * measured.w_shape)[None, :]


def _pairing(result: ModalResult, measured: MeasuredModes, spec: ObjectiveSpec):
    matching, _ = _options(spec)
    phi_a = result.at(measured.dofs) if measured.has_shapes else None
    return phi_a, pair_modes(
        result.frequencies_hz,
        measured.frequencies_hz,
        phi_a,
        measured.shapes,
        mac_threshold=0.0 if matching == "order" else spec.mac_threshold,
        frequency_window=None if matching == "order" else spec.frequency_window,
        method=matching if phi_a is not None else ("order" if matching == "order" else "frequency"),
    )


def reference_residuals(result: ModalResult, measured: MeasuredModes, spec: ObjectiveSpec):
    """Residual vector [r_lambda (m), shape terms] and the correlation it used."""
    _, weights = _options(spec)
    shapes = use_shape_term(measured, spec)
    eigenvector = shapes and _eigenvector_term(spec)
    phi_a, pairing = _pairing(result, measured, spec)
    idx, matched = pairing.analytical_index, pairing.matched
    fe = measured.frequencies_hz
    fa = np.full(fe.size, np.nan)
    fa[idx >= 0] = result.frequencies_hz[idx[idx >= 0]]
    lam_e, lam_a = eigenvalue_rad2_per_s2(fe), eigenvalue_rad2_per_s2(fa)
    per_mode = len(measured.dofs) if eigenvector else (2 if shapes else 1)
    unmatched = np.sqrt(spec.unmatched_penalty / per_mode)
    w_lam = eigenvalue_weights(measured, weights) * np.sqrt(spec.alpha * measured.w_frequency)
    r_lam = np.where(matched, w_lam * np.nan_to_num((lam_e - lam_a) / lam_e), unmatched)
    mac = pairing.mac if phi_a is not None else np.full(fe.size, np.nan)
    corr = ModeCorrelation(idx, fe, fa, (fa - fe) / fe, mac, matched)
    if not shapes:
        return r_lam, corr
    if eigenvector:
        return np.concatenate([r_lam, _eigenvector_residuals(phi_a, corr, measured, spec, unmatched)]), corr
    sq = np.sqrt(np.clip(np.nan_to_num(mac), 1e-12, 1.0))
    w_psi = shape_weights(measured, weights) * np.sqrt(spec.beta * measured.w_shape)
    r_psi = np.where(matched, w_psi * (1.0 - sq) / sq, unmatched)
    return np.concatenate([r_lam, r_psi]), corr


def _eigenvector_residuals(phi_a, corr: ModeCorrelation, measured: MeasuredModes, spec: ObjectiveSpec,
                           unmatched: float) -> np.ndarray:
    """Shape-entry differences (psi_e - psi_a) without the reference entries, mode after mode."""
    n_dof, m = len(measured.dofs), measured.n_modes
    q = reference_entries(measured.shapes)
    psi_e = normalize_at(measured.shapes, q)
    w = _eigenvector_weights(measured, spec)
    out = np.full((m, n_dof - 1), unmatched)
    for i in np.flatnonzero(corr.matched):
        phi = phi_a[:, corr.analytical_index[i]]
        if phi[q[i]] == 0.0:
            raise ModelEvaluationError(
                "zero_reference_entry", f"simulated mode {corr.analytical_index[i] + 1} is 0 at the reference "
                f"DOF {measured.dofs[q[i]]!r} of measured mode {i + 1}"
            )
        keep = np.delete(np.arange(n_dof), q[i])
        out[i] = w[keep, i] * (psi_e[keep, i] - phi[keep] / phi[q[i]])
    return out.ravel()


def reference_jacobian(result: ModalResult, derivatives, corr: ModeCorrelation, measured: MeasuredModes,
                       spec: ObjectiveSpec) -> np.ndarray:
    """d r / d theta (r, k) of :func:`reference_residuals` with the pairing held fixed (module docstring)."""
    _, weights = _options(spec)
    m = measured.n_modes
    shapes = use_shape_term(measured, spec)
    eigenvector = shapes and _eigenvector_term(spec)
    J = np.zeros((reference_n_residuals(measured, spec), len(derivatives.parameters)))
    w_lam = eigenvalue_weights(measured, weights) * np.sqrt(spec.alpha * measured.w_frequency)
    lam_e = eigenvalue_rad2_per_s2(measured.frequencies_hz)
    rows = measured_rows(result, measured) if shapes else None
    if eigenvector:
        q = reference_entries(measured.shapes)
        w = _eigenvector_weights(measured, spec)
        n_dof = len(measured.dofs)
    elif shapes:
        w_psi = shape_weights(measured, weights) * np.sqrt(spec.beta * measured.w_shape)
    for i in np.flatnonzero(corr.matched):
        a = int(corr.analytical_index[i])
        pos = derivatives.position(a)
        J[i] = -w_lam[i] * derivatives.dlambda[pos] / lam_e[i]
        if not shapes:
            continue
        phi = result.shapes[rows, a]
        dphi = derivatives.dphi[rows, pos, :]
        if eigenvector:
            keep = np.delete(np.arange(n_dof), q[i])
            ref = phi[q[i]]
            dpsi = (dphi[keep] - (phi[keep] / ref)[:, None] * dphi[q[i]][None, :]) / ref
            start = m + i * (n_dof - 1)
            J[start : start + n_dof - 1] = -w[keep, i][:, None] * dpsi
        else:
            mac = float(np.clip(corr.mac[i], 1e-12, 1.0))
            J[m + i] = w_psi[i] * shape_term_derivative(mac, mac_derivative(measured.shapes[:, i], phi, dphi))
    return J


def reference_n_residuals(measured: MeasuredModes, spec: ObjectiveSpec) -> int:
    """m eigenvalue terms, plus m MAC terms or m (n_dof - 1) eigenvector terms.

    Called when the problem is built, so unusable eigenvector weights (a zero standard
    deviation in use) are an input error there, not a failed evaluation later."""
    if use_shape_term(measured, spec) and _eigenvector_term(spec):
        _eigenvector_weights(measured, spec)
        return measured.n_modes * len(measured.dofs)
    return spec_n_residuals(measured, spec)


def reference_split(residuals: np.ndarray, measured: MeasuredModes, spec: ObjectiveSpec) -> np.ndarray:
    """Objective vector [Pi_lambda, Pi_shape]: eigenvalue terms, then every shape term (MAC or eigenvector)."""
    m = measured.n_modes
    r2 = np.asarray(residuals) ** 2
    return np.stack([r2[..., :m].sum(-1), r2[..., m:].sum(-1)], axis=-1)


FORMULATION = Formulation(
    reference_residuals,
    reference_n_residuals,  # [eigenvalue terms, shape terms]
    reference_split,
    objective_names=("Pi_lambda", "Pi_MAC"),  # the second is the shape term (MAC or eigenvector differences)
    check_options=check_options,
    jacobian=reference_jacobian,
)
