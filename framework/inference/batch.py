"""The Gaussian formulation's log-likelihood for a whole population in one call.

:mod:`framework.diagnosis.likelihood` evaluates its whitened residuals point by point (mode
pairing and the fitted shape scale per point), which costs ~10x the model solve of the
vectorized models and dominates a sampler's time. This module computes the same residuals for
n points at once, with the population pairing of :func:`framework.updating.objectives.pair_population`
(exact enumeration, as the SPEC formulation's batch path does):

    r_f,j = (f_a,j - f_e,j) / sigma_f,j,   r_s,kj = (c_j a_kj - e_kj) / s_kj,   c_j = a'We / a'Wa,

unmatched modes charged sqrt(chi2_u,j) on r_f,j (as there). The modes come from the model's
``modal_arrays`` in process, else from the runner (process or Dask backends) as a list of
ModalResult, so every backend gives the same numbers. When the population cannot be paired by
enumeration, or a point fails, or its shapes vanish, the problem's own ``evaluate`` is used
(tests check both paths agree to rounding).
"""

from __future__ import annotations

import numpy as np

from framework.models.arrays import ModalArrays, array_method
from framework.models.base import ModalResult, modal_many
from framework.updating.objectives import pair_population


def _modes(problem, theta: np.ndarray, runner):
    """(frequencies (n, m_a), shapes at the measured DOFs (n, d, m_a)) or None."""
    measured = problem.measured
    if runner is None or runner is modal_many:
        arrays = array_method(problem.model)
        if arrays is not None:
            modal = arrays(theta, problem.parameters.names)
            if modal.errors:
                return None
            index = {d: j for j, d in enumerate(modal.dofs)}
            if any(d not in index for d in measured.dofs):
                return None
            return modal.frequencies_hz, modal.shapes[:, [index[d] for d in measured.dofs], :]
    thetas = [problem.parameters.as_dict(t) for t in theta]
    results = runner(problem.model, thetas) if runner is not None else modal_many(problem.model, thetas)
    if isinstance(results, ModalArrays):
        results = results.results()
    if not all(isinstance(r, ModalResult) for r in results) or len({r.n_modes for r in results}) != 1:
        return None
    try:
        shapes = np.stack([r.at(measured.dofs) for r in results])
    except KeyError:
        return None
    return np.stack([r.frequencies_hz for r in results]), shapes


def gaussian_residuals_batch(problem, X: np.ndarray, runner=None) -> np.ndarray | None:
    """Modal residuals (n, r_m) of the Gaussian formulation at points X (n, k), or None when
    the batch path does not apply (the caller then uses ``problem.evaluate``)."""
    from framework.diagnosis.likelihood import unmatched_chi2, uses_shapes

    measured, spec = problem.measured, problem.spec
    if spec.formulation != "gaussian" or measured.frequency_std_hz is None or len(X) < 2:
        return None
    shape_rows = uses_shapes(measured, spec)
    if shape_rows and measured.shape_std is None:
        return None
    modes = _modes(problem, problem.parameters.to_physical(X), runner)
    if modes is None:
        return None
    freqs, shapes = modes
    if not np.all(np.isfinite(freqs)) or not np.all(np.isfinite(shapes)):
        return None
    if shape_rows and np.any(np.sum(shapes**2, axis=1) == 0):
        return None
    paired = pair_population(freqs, shapes, measured, spec, shape_rows)
    if paired is None:
        return None
    idx, _, matched = paired
    n = len(X)
    rows = np.arange(n)[:, None]
    fe, sf = measured.frequencies_hz, measured.frequency_std_hz
    fa = freqs[rows, idx]
    r_f = np.where(matched, (fa - fe) / sf, np.sqrt(unmatched_chi2(measured, spec))[None, :])
    if not shape_rows:
        return r_f
    e, s = measured.shapes, measured.shape_std
    a = np.take_along_axis(shapes, idx[:, None, :], axis=2)  # (n, d, m_e)
    w = 1.0 / s**2
    awa = np.sum(a * a * w, axis=1)
    c = np.where(awa > 0, np.sum(a * e * w, axis=1) / np.where(awa > 0, awa, 1.0), 0.0)
    r_s = (c[:, None, :] * a - e) / s
    r_s = np.where(matched[:, None, :], r_s, 0.0)
    return np.concatenate([r_f, np.swapaxes(r_s, 1, 2).reshape(n, -1)], axis=1)


def log_likelihood_batch(problem, noise, X: np.ndarray, runner=None) -> np.ndarray:
    """ln L at points X (n, k): the batch residuals where they apply, else ``problem.evaluate``."""
    R = gaussian_residuals_batch(problem, X, runner)
    if R is not None:
        return noise.log_likelihood(R)
    ev = problem.evaluate(X, runner)
    return noise.log_likelihood(ev.residuals, ev.ok)
