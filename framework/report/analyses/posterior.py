"""Derived tables of ``posterior`` studies, from their tables only (the kind's ``analyses``
hook); their figures: :mod:`framework.report.figures.posterior`.

- ``coverage`` (runs on simulated data, with a known truth): per structure, method
  (sampled, linearized) and parameter, the fraction of seeds whose 90 % interval holds the
  truth (``nominal``: 0.9);
- ``agreement`` (runs on measured data): per run and parameter, the shift of the sampled
  mean from the MAP in sampled standard deviations and the ratio of the linearized to the
  sampled standard deviation, and whether they agree.
"""

from __future__ import annotations

import pandas as pd

#: nominal coverage of the posterior intervals
NOMINAL = 0.9


def coverage_table(parameters: pd.DataFrame | None) -> pd.DataFrame | None:
    """structure, method, parameter, nominal, coverage, n_seeds from runs with a known truth."""
    if parameters is None or "covered_sampled" not in parameters or parameters["truth"].isna().all():
        return None
    df = parameters[parameters["truth"].notna()]
    keys = [c for c in ("structure", "variant") if c in df] + ["parameter"]
    rows = []
    for method, col in (("sampled", "covered_sampled"), ("linearized", "covered_linearized")):
        g = df.groupby(keys, sort=True)[col].agg(["mean", "count"]).reset_index()
        g = g.rename(columns={"mean": "coverage", "count": "n_seeds"})
        g.insert(len(keys) - 1, "method", method)
        g["nominal"] = NOMINAL
        rows.append(g)
    out = pd.concat(rows, ignore_index=True)
    first = ["structure", "method", "parameter", "nominal", "coverage", "n_seeds"]
    return out[[c for c in first if c in out] + [c for c in out if c not in first]]


def agreement_table(parameters: pd.DataFrame | None) -> pd.DataFrame | None:
    """Per run on measured data and parameter: sampled mean - MAP in sampled std, lin_std / std,
    and whether the sampled and linearized posteriors agree (|shift| <= 0.1, |ratio - 1| <= 0.2)."""
    if parameters is None or "mean_shift_std" not in parameters:
        return None
    if "truth" in parameters:  # runs on simulated data are summarized by the coverage table
        parameters = parameters[parameters["truth"].isna()]
        if parameters.empty:
            return None
    cols = [c for c in ("structure", "variant", "run_id", "seed", "parameter", "map", "mean", "lin_std", "std",
                        "mean_shift_std", "std_ratio") if c in parameters]
    out = parameters[cols].copy()
    out["agree"] = (out["mean_shift_std"].abs() <= 0.1) & ((out["std_ratio"] - 1).abs() <= 0.2)
    return out
