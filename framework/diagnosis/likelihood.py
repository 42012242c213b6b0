"""Gaussian likelihood of measured modes given a model's modes (the discrepancy statistics).

Noise model (independent Gaussian errors):

- frequency of measured mode j:   f_e,j = f_j + e,  e ~ N(0, sigma_f,j^2);
  sigma_f,j = ``frequency_std_hz`` of the data, else ``DEFAULT_FREQUENCY_STD_REL`` f_e,j;
- shape component k of mode j:    phi_e,kj = c_j phi_kj + e, e ~ N(0, s_kj^2) with an
  unknown scale c_j per mode; s_kj = ``shape_std`` of the data, else
  ``DEFAULT_SHAPE_STD_REL`` times the largest |phi_e| of the mode.

Whitened residuals of a matched pair (a = model, e = measured, W = diag(1 / s^2)):

    r_f,j  = (f_a,j - f_e,j) / sigma_f,j
    r_s,kj = (c_j a_kj - e_kj) / s_kj,   c_j = a' W e / a' W a   (least-squares scale)

so that sum_k r_s,kj^2 = e'We - (a'We)^2 / (a'Wa), the weighted form of
||e||^2 (1 - MAC). chi2 = sum r^2 and -2 ln L = chi2 + const (sigmas are known, so the
constant is the same for every model of the same data). Each mode contributes
1 + (n_dof - 1) data (one scale per mode is fitted).

Unmatched measured mode (no model mode with MAC >= ``mac_threshold`` within the
frequency window): it costs what a pair at the matching limit would cost,

    chi2_u,j = (window f_e,j / sigma_f,j)^2 + (1 - mac_threshold) e'We,

so that leaving a mode unmatched is never cheaper than matching it badly (the penalty is
carried by r_f,j; the shape residuals are 0). Pairing: :func:`framework.updating.objectives.correlate`
(highest MAC, one-to-one; nearest frequency without shapes).

The likelihood is the objective formulation ``"gaussian"`` (named in the static table
:data:`framework.updating.objectives.FORMULATIONS`) so that the framework's
:class:`~framework.updating.problem.UpdatingProblem` and optimizers calibrate with it.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from framework.measured.modes import MeasuredModes
from framework.models.base import ModalResult
from framework.updating.objectives import Formulation, ObjectiveSpec, correlate

#: sigma_f / f assumed when the data give no frequency_std_hz (1 %: the upper end of the
#: scatter of identified frequencies between repeated tests of civil structures; a
#: conservative assumption, stated in every summary, see workflow.noise_warning)
DEFAULT_FREQUENCY_STD_REL = 0.01
#: shape std as a fraction of the mode's largest measured component when no shape_std (5 %)
DEFAULT_SHAPE_STD_REL = 0.05
#: relative frequency distance that an unmatched mode is charged (see module docstring)
DEFAULT_UNMATCHED_WINDOW = 0.1
FORMULATION_NAME = "gaussian"


def with_noise_model(
    measured: MeasuredModes,
    frequency_std_rel: float = DEFAULT_FREQUENCY_STD_REL,
    shape_std_rel: float = DEFAULT_SHAPE_STD_REL,
) -> MeasuredModes:
    """Copy of ``measured`` with frequency_std_hz and shape_std filled by the defaults where absent."""
    f_std = measured.frequency_std_hz
    if f_std is None:
        f_std = frequency_std_rel * measured.frequencies_hz
    s_std = measured.shape_std
    if measured.has_shapes and s_std is None:
        peak = np.max(np.abs(measured.shapes), axis=0)
        s_std = np.broadcast_to(shape_std_rel * peak, measured.shapes.shape).copy()
    if np.any(np.asarray(f_std) <= 0) or (s_std is not None and np.any(np.asarray(s_std) <= 0)):
        from framework.core.errors import InputError

        raise InputError(f"{measured.source}: frequency_std_hz and shape_std must be > 0 for the likelihood")
    return replace(measured, frequency_std_hz=np.asarray(f_std, float), shape_std=s_std)


def uses_shapes(measured: MeasuredModes, spec: ObjectiveSpec) -> bool:
    return bool(spec.use_shapes and measured.has_shapes)


def n_data(measured: MeasuredModes, spec: ObjectiveSpec) -> int:
    """Number of independent data: m frequencies + m (n_dof - 1) shape components."""
    m = measured.n_modes
    return m + (m * (len(measured.dofs) - 1) if uses_shapes(measured, spec) else 0)


def n_residuals(measured: MeasuredModes, spec: ObjectiveSpec) -> int:
    m = measured.n_modes
    return m + (m * len(measured.dofs) if uses_shapes(measured, spec) else 0)


def unmatched_chi2(measured: MeasuredModes, spec: ObjectiveSpec) -> np.ndarray:
    """chi2_u,j charged for each measured mode when it is unmatched."""
    window = float(spec.options.get("unmatched_window", DEFAULT_UNMATCHED_WINDOW))
    sf = _frequency_std(measured)
    out = (window * measured.frequencies_hz / sf) ** 2
    if uses_shapes(measured, spec):
        e, s = measured.shapes, measured.shape_std
        out = out + (1.0 - spec.mac_threshold) * np.sum((e / s) ** 2, axis=0)
    return out


def _frequency_std(measured: MeasuredModes) -> np.ndarray:
    if measured.frequency_std_hz is None:
        return DEFAULT_FREQUENCY_STD_REL * measured.frequencies_hz
    return measured.frequency_std_hz


def gaussian_residuals(result: ModalResult, measured: MeasuredModes, spec: ObjectiveSpec):
    """Whitened residual vector [r_f (m), r_s (m * n_dof)] and the correlation it used."""
    corr = correlate(result, measured, spec)
    sf = _frequency_std(measured)
    r_f = np.where(corr.matched, np.nan_to_num(corr.f_model_hz - corr.f_measured_hz) / sf, 0.0)
    r_f = np.where(corr.matched, r_f, np.sqrt(unmatched_chi2(measured, spec)))
    if not uses_shapes(measured, spec):
        return r_f, corr
    e = measured.shapes
    s = measured.shape_std if measured.shape_std is not None else np.full_like(e, DEFAULT_SHAPE_STD_REL)
    a_all = result.at(measured.dofs)
    idx = np.maximum(corr.analytical_index, 0)
    a = a_all[:, idx]
    w = 1.0 / s**2
    awa = np.sum(a * a * w, axis=0)
    c = np.where(awa > 0, np.sum(a * e * w, axis=0) / np.where(awa > 0, awa, 1.0), 0.0)
    r_s = (c * a - e) / s
    r_s[:, ~corr.matched] = 0.0
    return np.concatenate([r_f, r_s.T.ravel()]), corr


def split_chi2(residuals: np.ndarray, measured: MeasuredModes, spec: ObjectiveSpec) -> np.ndarray:
    """[chi2_frequency, chi2_shape] from residual rows (..., r)."""
    m = measured.n_modes
    r2 = np.asarray(residuals) ** 2
    f = r2[..., :m].sum(-1)
    s = r2[..., m:].sum(-1) if uses_shapes(measured, spec) else np.zeros_like(f)
    return np.stack([f, s], axis=-1)


def per_mode_chi2(residuals: np.ndarray, measured: MeasuredModes, spec: ObjectiveSpec) -> tuple[np.ndarray, np.ndarray]:
    """chi2 per measured mode: (frequency part (m,), shape part (m,))."""
    m = measured.n_modes
    r = np.asarray(residuals)
    f = r[:m] ** 2
    if not uses_shapes(measured, spec):
        return f, np.zeros(m)
    s = (r[m : m + m * len(measured.dofs)] ** 2).reshape(m, len(measured.dofs)).sum(axis=1)
    return f, s


def check_options(options: dict) -> None:
    """The Gaussian formulation reads one option, ``unmatched_window`` (a number > 0)."""
    unknown = sorted(set(options) - {"unmatched_window"})
    if unknown:
        raise ValueError(f"unknown key(s) {unknown} for formulation 'gaussian'; known: ['unmatched_window']")
    window = options.get("unmatched_window", DEFAULT_UNMATCHED_WINDOW)
    if isinstance(window, bool) or not isinstance(window, (int, float)) or not 0 < window < float("inf"):
        raise ValueError(f"unmatched_window must be a finite number > 0, got {window!r}")


FORMULATION = Formulation(
    gaussian_residuals,
    n_residuals,
    split_chi2,
    objective_names=("chi2_frequency", "chi2_shape"),
    check_options=check_options,
)


def objective_spec(
    mac_threshold: float = 0.5,
    frequency_window: float | None = None,
    unmatched_window: float = DEFAULT_UNMATCHED_WINDOW,
    use_shapes: bool = True,
) -> ObjectiveSpec:
    """ObjectiveSpec selecting the Gaussian formulation; Pi = chi2 (failures cost 1e12)."""
    return ObjectiveSpec(
        formulation=FORMULATION_NAME,
        mac_threshold=mac_threshold,
        frequency_window=frequency_window,
        use_shapes=use_shapes,
        failure_penalty=1e12,
        options={"unmatched_window": unmatched_window},
    )
