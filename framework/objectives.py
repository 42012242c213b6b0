"""Objective functions of model updating (SPEC 3), as a residual vector first.

For measured modes i = 1..m paired with analytical modes:

    eps_i = (f_a,i - f_e,i) / f_e,i                      relative frequency error
    r_f,i = sqrt(alpha w_f,i) eps_i
    r_s,i = sqrt(beta w_s,i) (1 - sqrt(MAC_i)) / sqrt(MAC_i)
    Pi    = sum r_f,i^2 + sum r_s,i^2 = alpha Pi_f + beta Pi_MAC   (+ penalty terms)

so the scalar objective, the residual vector (least squares, sensitivity method) and the
objective vector [Pi_f, Pi_MAC] (NSGA-II) are three views of one definition.

- An unmatched measured mode (no analytical partner with MAC >= threshold) is never
  paired silently: its two residuals are set to sqrt(unmatched_penalty / 2) each, so it
  adds ``unmatched_penalty`` to Pi.
- A failed model evaluation has every residual equal to sqrt(failure_penalty / r), so
  Pi = failure_penalty (default 1e3, far above any physical misfit).
- Penalty terms (appended residuals):
  ratio constraint   sqrt(w |theta_a/theta_b - theta_a,0/theta_b,0|)   (bridge soft constraint)
  regularization     sqrt(tau) (z - z_0), z the parameters as ratios to initial values
                     ("ratio") or normalized to their bounds ("normalized")  (Tikhonov)

A formulation maps (modal result, measured modes, spec) to residuals; "spec" is the one
above. Other formulations (e.g. a peer package's) register in ``FORMULATIONS``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from framework.correlation import pair_modes
from framework.errors import InputError
from framework.measurements import MeasuredModes
from framework.models.base import ModalResult
from framework.parameters import ParameterSet


@dataclass(frozen=True)
class RatioConstraint:
    """Soft constraint w |theta_a/theta_b - theta_a,0/theta_b,0| (SPEC 3, bridge: w = 2e-4)."""

    numerator: str
    denominator: str
    weight: float = 2e-4


@dataclass(frozen=True)
class ObjectiveSpec:
    """Settings of the objective. alpha/beta weight the frequency and MAC terms.

    pairing: "mac" (highest MAC, one-to-one), "order" or "frequency"; mac_threshold: a
    pair below it is unmatched; frequency_window: relative window for MAC pairing
    (None = any); use_shapes: include the MAC term (needs measured shapes).
    """

    alpha: float = 1.0
    beta: float = 1.0
    use_shapes: bool = True
    pairing: str = "mac"
    mac_threshold: float = 0.5
    frequency_window: float | None = None
    unmatched_penalty: float = 1.0
    failure_penalty: float = 1e3
    ratio_constraints: tuple[RatioConstraint, ...] = ()
    regularization_tau: float = 0.0
    regularization_space: str = "ratio"
    formulation: str = "spec"
    options: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name in ("alpha", "beta", "unmatched_penalty", "failure_penalty", "regularization_tau"):
            value = getattr(self, name)
            if not np.isfinite(value) or value < 0:
                raise InputError(f"objective.{name} must be a finite number >= 0, got {value!r}")
        if self.pairing not in ("mac", "order", "frequency"):
            raise InputError(f"objective.pairing must be 'mac', 'order' or 'frequency', got {self.pairing!r}")
        if not 0.0 <= self.mac_threshold <= 1.0:
            raise InputError(f"objective.mac_threshold must be in [0, 1], got {self.mac_threshold!r}")
        if self.regularization_space not in ("ratio", "normalized"):
            raise InputError(
                f"objective.regularization_space must be 'ratio' or 'normalized', got {self.regularization_space!r}"
            )
        if self.formulation not in FORMULATIONS:
            raise InputError(
                f"objective.formulation {self.formulation!r} unknown; known: {sorted(FORMULATIONS)}"
            )


@dataclass(frozen=True)
class ModeCorrelation:
    """Per measured mode: paired analytical index (-1 unmatched), frequencies, eps, MAC."""

    analytical_index: np.ndarray
    f_measured_hz: np.ndarray
    f_model_hz: np.ndarray
    frequency_error: np.ndarray
    mac: np.ndarray
    matched: np.ndarray


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


def correlate(result: ModalResult, measured: MeasuredModes, spec: ObjectiveSpec) -> ModeCorrelation:
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


def spec_residuals(result: ModalResult, measured: MeasuredModes, spec: ObjectiveSpec):
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


def spec_residuals_batch(freqs: np.ndarray, shapes: np.ndarray, measured: MeasuredModes, spec: ObjectiveSpec):
    """Vectorized :func:`spec_residuals` for a population with equal mode counts.

    freqs (n, m_a), shapes (n, n_dof, m_a) already restricted to the measured DOFs (or None).
    Returns residuals (n, r) and per-point ModeCorrelation, or None if the population is
    too large to pair by enumeration (the caller then uses the per-point path).
    """
    from framework.correlation import mac_matrix_batch, pair_modes_batch

    use_shapes = spec.use_shapes and measured.has_shapes
    mm = mac_matrix_batch(shapes, measured.shapes) if use_shapes else None
    method = spec.pairing if use_shapes else ("order" if spec.pairing == "order" else "frequency")
    paired = pair_modes_batch(freqs, measured.frequencies_hz, mm, mac_threshold=spec.mac_threshold,
                              frequency_window=spec.frequency_window, method=method)
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
    corrs = [ModeCorrelation(idx[i], fe, fa[i], eps[i], mac_out[i], matched[i]) for i in range(n)]
    return r, corrs


def use_shape_term(measured: MeasuredModes, spec: ObjectiveSpec) -> bool:
    return bool(spec.use_shapes and measured.has_shapes and spec.beta > 0)


def spec_n_residuals(measured: MeasuredModes, spec: ObjectiveSpec) -> int:
    return measured.n_modes * (2 if use_shape_term(measured, spec) else 1)


def spec_split(residuals: np.ndarray, measured: MeasuredModes, spec: ObjectiveSpec) -> np.ndarray:
    """Objective vector [Pi_f, Pi_MAC] from the modal residuals (..., r)."""
    m = measured.n_modes
    r2 = np.asarray(residuals) ** 2
    pi_f = r2[..., :m].sum(-1)
    pi_s = r2[..., m : 2 * m].sum(-1) if use_shape_term(measured, spec) else np.zeros_like(pi_f)
    return np.stack([pi_f, pi_s], axis=-1)


@dataclass(frozen=True)
class Formulation:
    """A residual formulation: residuals(result, measured, spec) -> (r, correlation)."""

    residuals: Callable
    n_residuals: Callable
    split: Callable
    objective_names: tuple[str, ...] = ("Pi_f", "Pi_MAC")
    #: optional vectorized residuals(freqs (n, m), shapes (n, dof, m), measured, spec)
    batch_residuals: Callable | None = None


FORMULATIONS: dict[str, Formulation] = {
    "spec": Formulation(spec_residuals, spec_n_residuals, spec_split, batch_residuals=spec_residuals_batch),
}


#: Formulations defined in other modules, imported on first use: name -> "module:attribute".
LAZY_FORMULATIONS: dict[str, str] = {
    "reference": "framework.reference_formulation:FORMULATION",
    "gaussian": "framework.discrepancy.likelihood:FORMULATION",
}


def get_formulation(name: str) -> Formulation:
    """The formulation called ``name`` (built-in, registered, or lazily imported)."""
    if name not in FORMULATIONS and name in LAZY_FORMULATIONS:
        import importlib

        module, attr = LAZY_FORMULATIONS[name].split(":")
        FORMULATIONS[name] = getattr(importlib.import_module(module), attr)
    if name not in FORMULATIONS:
        known = sorted(set(FORMULATIONS) | set(LAZY_FORMULATIONS))
        raise InputError(f"objective.formulation {name!r} unknown; known: {known}")
    return FORMULATIONS[name]


def register_formulation(name: str, formulation: Formulation) -> None:
    """Make a residual formulation selectable as ObjectiveSpec(formulation=name)."""
    FORMULATIONS[name] = formulation


def penalty_residuals(
    theta: np.ndarray, x: np.ndarray, parameters: ParameterSet, spec: ObjectiveSpec
) -> np.ndarray:
    """Residuals of the ratio constraints and the Tikhonov term for points theta (n, k)."""
    theta = np.atleast_2d(theta)
    x = np.atleast_2d(x)
    parts = []
    names = parameters.names
    for c in spec.ratio_constraints:
        a, b = names.index(c.numerator), names.index(c.denominator)
        r0 = parameters.initial[a] / parameters.initial[b]
        d = np.abs(theta[:, a] / theta[:, b] - r0)
        parts.append(np.sqrt(c.weight * d)[:, None])
    if spec.regularization_tau > 0:
        if spec.regularization_space == "ratio":
            z = parameters.to_ratio(theta)
            z0 = np.ones(len(parameters))
        else:
            z, z0 = x, parameters.x_initial
        parts.append(np.sqrt(spec.regularization_tau) * (z - z0))
    if not parts:
        return np.zeros((theta.shape[0], 0))
    return np.concatenate(parts, axis=1)


def n_penalty_residuals(parameters: ParameterSet, spec: ObjectiveSpec) -> int:
    return len(spec.ratio_constraints) + (len(parameters) if spec.regularization_tau > 0 else 0)


def check_constraints(parameters: ParameterSet, spec: ObjectiveSpec) -> None:
    """Ratio constraints must name updated parameters."""
    for c in spec.ratio_constraints:
        for name in (c.numerator, c.denominator):
            if name not in parameters.names:
                raise InputError(
                    f"objective.ratio_constraints: parameter {name!r} is not updated; updated: {parameters.names}"
                )
