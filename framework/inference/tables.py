"""Table columns of the linearized uncertainty of one updating run (used by the ``updating``
run kind): one Jacobian at the optimum, never fatal (a failure is recorded as ``uq_error``)."""

from __future__ import annotations

import logging

import numpy as np

from framework.inference.evidence import laplace_log_evidence
from framework.inference.likelihood import Prior, noise_model
from framework.inference.linearized import at_optimum

log = logging.getLogger(__name__)


def linearized_columns(problem, x_best: np.ndarray, residuals: np.ndarray | None = None, runner=None) -> dict:
    """{"run": columns of the runs row, "parameters": one dict of columns per parameter,
    "identifiability": rows}: chi2, n_data, Laplace ln Z, where the data's standard deviations
    came from (``noise_frequency_source``, ``noise_shape_source``: data / estimated / assumed,
    "" for shapes not used); std, 90 % interval and the noise assumption per parameter;
    singular directions."""
    k = problem.n_params
    nan_params = [{"std": np.nan, "ci90_lower": np.nan, "ci90_upper": np.nan, "noise_assumed": ""} for _ in range(k)]
    out = {"run": {"chi2": np.nan, "n_data": np.nan, "log_evidence_laplace": np.nan, "uq_jacobian": "",
                   "uq_error": "", "noise_frequency_source": "", "noise_shape_source": ""},
           "parameters": nan_params, "identifiability": []}
    try:
        noise = noise_model(problem)
        for row in nan_params:
            row["noise_assumed"] = noise.assumed
        out["run"].update(noise_frequency_source=noise.sources["frequency"], noise_shape_source=noise.sources["shape"])
        if residuals is None:
            residuals = problem.residuals(x_best, runner)
        chi2 = float(noise.chi2(residuals)[0])
        prior = Prior(problem.parameters)
        lin = at_optimum(problem, x_best, noise, prior, runner)
        lo, hi = lin.interval(0.9)
        theta = problem.parameters.to_physical(np.asarray(x_best, float))
        ln_l = float(noise.log_likelihood(residuals)[0])
        ln_z = laplace_log_evidence(ln_l, float(prior.log_pdf(theta)[0]), lin.hessian_x, prior.span)
        out["run"].update(chi2=chi2, n_data=noise.n_data, log_evidence_laplace=ln_z, uq_jacobian=lin.jacobian_method)
        out["parameters"] = [{"std": float(s), "ci90_lower": float(a), "ci90_upper": float(b),
                              "noise_assumed": noise.assumed} for s, a, b in zip(lin.std, lo, hi)]
        out["identifiability"] = lin.identifiability_rows()
    except Exception as exc:  # the uncertainty is a by-product: its failure never ends the run
        log.debug("linearized uncertainty failed: %s", exc)
        out["run"]["uq_error"] = f"{type(exc).__name__}: {exc}"
    return out
