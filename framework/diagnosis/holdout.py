"""Prediction of held-out modes: leave-one-mode-out predictive chi2.

For a model (current or enriched) and each measured mode j: re-calibrate on the other
modes (warm-started at the full-data estimate), predict mode j, and charge its chi2
(frequency and shape residuals of mode j, or the unmatched cost when the prediction has
no partner). LOO = sum_j chi2_j is a plug-in estimate of -2 x the log predictive
density of new modes (up to a constant): a model that merely fits noise with its extra
parameters predicts held-out modes no better than the simpler model.
"""

from __future__ import annotations

import numpy as np

from framework.diagnosis.calibrate import Fit, calibrate
from framework.diagnosis.effects import Catalogue
from framework.measured.modes import MeasuredModes
from framework.updating.formulations import gaussian
from framework.updating.objectives import ObjectiveSpec
from framework.updating.problem import UpdatingProblem


def loo_chi2(
    catalogue: Catalogue,
    fit: Fit,
    measured: MeasuredModes,
    spec: ObjectiveSpec,
    max_evaluations: int = 200,
) -> tuple[float, np.ndarray]:
    """Total and per-mode leave-one-mode-out predictive chi2 of ``fit``'s model."""
    model = catalogue.model(fit.active)
    params = catalogue.parameters(fit.active)
    full = UpdatingProblem(model, measured, params, spec)
    x_fit = params.to_normalized(fit.theta)
    m = measured.n_modes
    out = np.empty(m)
    for j in range(m):
        sub = measured.select([i for i in range(m) if i != j])
        f = calibrate(
            model, sub, parameters=params, spec=spec, n_starts=1, x_starts=[x_fit],
            max_evaluations=max_evaluations, label=f"{fit.label} without mode {j + 1}", active=fit.active,
        )  # fmt: skip
        ev = full.evaluate(params.to_normalized(f.theta)[None, :])
        chi_f, chi_s = gaussian.per_mode_chi2(ev.residuals[0], measured, spec)
        out[j] = chi_f[j] + chi_s[j]
    return float(out.sum()), out
