"""Detect: is what remains after calibration explainable by measurement noise?

With Gaussian noise of known sigma (the data's standard deviations, else the assumed
defaults of :mod:`framework.inference.noise`) and a model that contains the truth, the
calibrated chi2 follows (to first order) a chi-square distribution with n - k degrees of
freedom (n data, k calibrated parameters; :func:`framework.inference.noise.consistency_test`).
The discrepancy is *significant* when

    p = P(chi2_{n-k} >= chi2_min) < alpha        (default alpha = 0.01)

or when any measured mode is unmatched (no model mode with MAC >= threshold: a missing
mode cannot be noise). Reported besides: standardized frequency residual z_j per mode,
shape chi2 per mode with its p-value (n_dof - 1 degrees of freedom), COMAC per sensor
over the matched modes (low COMAC localizes the disagreement), and the residual
pattern: the least-squares slope of z_j against mode order and the number of sign runs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import stats

from framework.core.correlation import comac
from framework.diagnosis.calibrate import Fit, gaussian_spec
from framework.inference.noise import consistency_test
from framework.measured.modes import MeasuredModes
from framework.updating.formulations import gaussian
from framework.updating.objectives import ObjectiveSpec

DEFAULT_ALPHA = 0.01


@dataclass
class Detection:
    """Outcome of the discrepancy test of one calibrated model."""

    chi2: float
    dof: int
    p_value: float
    alpha: float
    n_unmatched: int
    significant: bool
    modes: pd.DataFrame
    comac: pd.DataFrame
    z_slope: float
    sign_runs: int

    def summary(self) -> dict:
        return {
            "chi2": self.chi2,
            "dof": self.dof,
            "p_value": self.p_value,
            "alpha": self.alpha,
            "n_unmatched": self.n_unmatched,
            "significant": self.significant,
            "z_slope_per_mode": self.z_slope,
            "sign_runs": self.sign_runs,
            "lowest_comac_sensor": (str(self.comac.sort_values("comac").iloc[0]["sensor"]) if len(self.comac) else ""),
            "lowest_comac": float(self.comac["comac"].min()) if len(self.comac) else float("nan"),
        }


def detect(
    fit: Fit, measured: MeasuredModes, spec: ObjectiveSpec | None = None, alpha: float = DEFAULT_ALPHA
) -> Detection:
    """Test the calibrated residuals of ``fit`` against the noise model."""
    spec = spec or gaussian_spec()
    dof, p = consistency_test(fit.chi2, fit.n_data, fit.k)
    corr = fit.correlation
    chi_f, chi_s = gaussian.per_mode_chi2(fit.residuals, measured, spec)
    m = measured.n_modes
    z = fit.residuals[:m].copy()
    z[~corr.matched] = np.nan
    shape_dof = max(len(measured.dofs) - 1, 1)
    use_shapes = gaussian.uses_shapes(measured, spec)
    modes = pd.DataFrame(
        {
            "mode": np.arange(1, m + 1),
            "label": list(measured.labels),
            "matched": corr.matched,
            "z_frequency": z,
            "chi2_shape": np.where(corr.matched, chi_s, np.nan) if use_shapes else np.nan,
            "p_shape": np.where(corr.matched, stats.chi2.sf(chi_s, shape_dof), np.nan) if use_shapes else np.nan,
        }
    )
    ok = corr.matched
    zs = z[ok]
    order = np.arange(1, m + 1)[ok]
    slope = float(np.polyfit(order, zs, 1)[0]) if zs.size >= 2 else float("nan")
    signs = np.sign(zs[zs != 0])
    runs = int(1 + np.sum(signs[1:] != signs[:-1])) if signs.size else 0
    if use_shapes and ok.sum() >= 1:
        phi_a = fit.modal.at(measured.dofs)[:, corr.analytical_index[ok]]
        values = comac(phi_a, measured.shapes[:, ok])
        com = pd.DataFrame({"sensor": list(measured.dofs), "comac": values})
    else:
        com = pd.DataFrame({"sensor": [], "comac": []})
    n_un = int(np.sum(~corr.matched))
    return Detection(
        chi2=float(fit.chi2),
        dof=dof,
        p_value=p,
        alpha=alpha,
        n_unmatched=n_un,
        significant=bool(p < alpha or n_un > 0),
        modes=modes,
        comac=com,
        z_slope=slope,
        sign_runs=runs,
    )
