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

Exact Jacobians (:func:`spec_jacobian`, :func:`penalty_jacobian`; used by
:meth:`framework.updating.problem.UpdatingProblem.jacobian`) hold the pairing fixed:
d eps_i = df_a / f_e,i with df = dlambda / (8 pi^2 f); d[(1 - sqrt MAC)/sqrt MAC] =
-dMAC / (2 MAC^1.5) with the MAC derivative of :func:`mac_derivative`.

A formulation maps (modal result, measured modes, spec) to residuals; "spec" is the one
above. Every formulation is named in the static table ``FORMULATIONS`` (name ->
"module:attribute", resolved on use); a new one is one line there.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Annotated, Any, ClassVar, Literal

import numpy as np
from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    StrictBool,
    StrictStr,
    ValidationError,
    ValidationInfo,
    field_validator,
    model_validator,
)

from framework.core.correlation import pair_modes
from framework.core.errors import InputError
from framework.core.parameters import ParameterSet
from framework.measured.modes import MeasuredModes
from framework.models.base import ModalResult


def _no_bool(value):
    """Reject booleans and text where a number is expected (pydantic would read True as 1.0
    and '1' as 1.0)."""
    if isinstance(value, bool | str | bytes):
        raise ValueError(f"expected a number, got {value!r}")
    return value


Number = Annotated[float, BeforeValidator(_no_bool)]


class _Frozen(BaseModel):
    """Frozen pydantic model that accepts positional fields and raises InputError naming the field.

    Nested in a config, pydantic validates it directly (a ``ValidationError`` whose location
    names the field); constructed in Python (``ObjectiveSpec(alpha=...)``) a bad value raises
    :class:`~framework.core.errors.InputError` "objective.<field>: <message> (value ...)".
    """

    model_config = ConfigDict(frozen=True, extra="forbid")
    _where: ClassVar[str] = "objective"

    def __init__(self, *args, **kwargs):
        names = list(type(self).model_fields)
        if len(args) > len(names):
            raise InputError(f"{self._where}: at most {len(names)} positional values, got {len(args)}")
        for name, value in zip(names, args):
            if name in kwargs:
                raise InputError(f"{self._where}.{name}: given twice")
            kwargs[name] = value
        try:
            super().__init__(**kwargs)
        except ValidationError as exc:
            raise InputError(validation_message(exc, self._where)) from None

    # pydantic calls a custom __init__ also when it validates the model nested in another
    # (a config); this flag keeps nested validation on pydantic's own path, so that a
    # config error stays a ValidationError located at its field
    __init__.__pydantic_base_init__ = True  # type: ignore[attr-defined]


def validation_message(exc: ValidationError, where: str) -> str:
    """One line naming the field, the problem and the value of a pydantic error."""
    first = exc.errors()[0]
    loc = ".".join(str(p) for p in (where, *first["loc"]) if p != "")
    msg = "unknown key" if first["type"] == "extra_forbidden" else first["msg"].removeprefix("Value error, ")
    if not first["loc"]:  # a rule over several fields: the input is the whole mapping
        return f"{loc}: {msg}"
    return f"{loc}: {msg} (value {first.get('input')!r})"


class RatioConstraint(_Frozen):
    """Soft constraint w |theta_a/theta_b - theta_a,0/theta_b,0| (SPEC 3, bridge: w = 2e-4)."""

    _where: ClassVar[str] = "objective.ratio_constraints"

    numerator: str
    denominator: str
    weight: Number = Field(2e-4, ge=0, allow_inf_nan=False)


class ObjectiveSpec(_Frozen):
    """Settings of the objective, and the config schema of ``objective:``.

    alpha/beta weight the frequency and MAC terms (not both 0: Pi would be identically 0).
    pairing: "mac" (highest MAC, one-to-one), "order" or "frequency"; mac_threshold: a
    pair below it is unmatched; frequency_window: relative window for MAC pairing
    (None = any); use_shapes: include the MAC term (needs measured shapes);
    unmatched_penalty: Pi added per unmatched mode; failure_penalty (> 0): Pi of a failed
    evaluation; ratio_constraints, regularization_tau (Tikhonov weight) and
    regularization_space ("ratio" or "normalized"): penalty terms; formulation: a name of
    :data:`FORMULATIONS`, whose ``options`` are checked here.
    """

    alpha: Number = Field(1.0, ge=0, allow_inf_nan=False)
    beta: Number = Field(1.0, ge=0, allow_inf_nan=False)
    use_shapes: StrictBool = True
    pairing: Literal["mac", "order", "frequency"] = "mac"
    mac_threshold: Number = Field(0.5, ge=0, le=1)
    frequency_window: Number | None = Field(None, gt=0, allow_inf_nan=False)
    unmatched_penalty: Number = Field(1.0, ge=0, allow_inf_nan=False)
    failure_penalty: Number = Field(1e3, gt=0, allow_inf_nan=False)
    ratio_constraints: tuple[RatioConstraint, ...] = ()
    regularization_tau: Number = Field(0.0, ge=0, allow_inf_nan=False)
    regularization_space: Literal["ratio", "normalized"] = "ratio"
    formulation: StrictStr = "spec"
    options: dict[str, Any] = Field(default_factory=dict)

    @field_validator("formulation")
    @classmethod
    def _known_formulation(cls, name: str) -> str:
        if name not in FORMULATIONS:
            raise ValueError(f"unknown formulation {name!r}; known: {sorted(FORMULATIONS)}")
        return name

    @field_validator("options")
    @classmethod
    def _formulation_options(cls, options: dict, info: ValidationInfo) -> dict:
        name = info.data.get("formulation")
        if name is not None:  # else the formulation itself was rejected
            check = get_formulation(name).check_options
            if check is not None:
                check(options)
        return options

    @model_validator(mode="after")
    def _not_identically_zero(self):
        if self.alpha == 0 and self.beta == 0:
            raise ValueError("alpha and beta are both 0: the objective would be identically 0")
        return self


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


def pair_population(freqs: np.ndarray, shapes: np.ndarray | None, measured: MeasuredModes, spec: ObjectiveSpec,
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


def spec_residuals_batch(freqs: np.ndarray, shapes: np.ndarray, measured: MeasuredModes, spec: ObjectiveSpec):
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


def spec_jacobian(result: ModalResult, derivatives, corr: ModeCorrelation, measured: MeasuredModes,
                  spec: ObjectiveSpec) -> np.ndarray:
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
    #: optional vectorized residuals(freqs (n, m), shapes (n, dof, m), measured, spec) ->
    #: (residuals (n, r), ModeCorrelations), or None when it cannot (the per-point path is used)
    batch_residuals: Callable | None = None
    #: optional check of ``ObjectiveSpec.options`` (raises ValueError naming the key); None:
    #: the formulation reads no options
    check_options: Callable[[dict], None] | None = None
    #: optional exact Jacobian jacobian(result, derivatives, correlation, measured, spec) -> (r, k)
    #: d residuals / d theta from :class:`~framework.core.modal_derivatives.ModalDerivatives` of the
    #: paired modes (pairing held fixed); None: finite differences only
    jacobian: Callable | None = None


SPEC_FORMULATION = Formulation(spec_residuals, spec_n_residuals, spec_split, batch_residuals=spec_residuals_batch,
                               jacobian=spec_jacobian)

#: Every selectable formulation: name -> "module:attribute", imported when first used, so
#: that which names are valid never depends on which modules happen to be imported.
FORMULATIONS: dict[str, str] = {
    "spec": "framework.updating.objectives:SPEC_FORMULATION",
    "reference": "framework.updating.reference_formulation:FORMULATION",
    "gaussian": "framework.diagnosis.likelihood:FORMULATION",
}


def get_formulation(name: str) -> Formulation:
    """The formulation called ``name`` (one of :data:`FORMULATIONS`)."""
    if name not in FORMULATIONS:
        raise InputError(f"objective.formulation {name!r} unknown; known: {sorted(FORMULATIONS)}")
    module, attr = FORMULATIONS[name].split(":")
    return getattr(importlib.import_module(module), attr)


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


def penalty_jacobian(theta: np.ndarray, parameters: ParameterSet, spec: ObjectiveSpec) -> np.ndarray:
    """d (penalty residuals) / d theta (n_pen, k) at one point theta (k,).

    Ratio constraint r = sqrt(w |d|), d = theta_a/theta_b - r_0: dr = sqrt(w) sign(d) dd / (2 sqrt|d|)
    with dd/dtheta_a = 1/theta_b, dd/dtheta_b = -theta_a/theta_b^2 (not differentiable at d = 0,
    where the zero subgradient is used). Tikhonov: sqrt(tau)/theta_0,j ("ratio") or
    sqrt(tau)/(upper_j - lower_j) ("normalized") on the diagonal.
    """
    theta = np.asarray(theta, float)
    k = theta.size
    names = parameters.names
    rows = []
    for c in spec.ratio_constraints:
        a, b = names.index(c.numerator), names.index(c.denominator)
        d = theta[a] / theta[b] - parameters.initial[a] / parameters.initial[b]
        row = np.zeros(k)
        if d != 0.0:
            scale = np.sqrt(c.weight) * np.sign(d) / (2.0 * np.sqrt(abs(d)))
            row[a] += scale / theta[b]
            row[b] -= scale * theta[a] / theta[b] ** 2
        rows.append(row[None, :])
    if spec.regularization_tau > 0:
        if spec.regularization_space == "ratio":
            with np.errstate(divide="ignore"):
                diag = np.where(parameters.initial != 0, 1.0 / parameters.initial, np.nan)
        else:
            diag = 1.0 / (parameters.upper - parameters.lower)
        rows.append(np.sqrt(spec.regularization_tau) * np.diag(diag))
    if not rows:
        return np.zeros((0, k))
    return np.concatenate(rows, axis=0)


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
