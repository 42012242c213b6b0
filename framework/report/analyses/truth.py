"""Updated parameters against known true values (studies on simulated data).

Asked for with ``report: {truth: {parameters: {kyy: 8950.0, kxx: 17300.0, ...}}}`` in an
``updating`` study; writes ``parameter_error.csv``: one row per run and parameter with a
true value: label, variant, seed, algorithm, parameter, unit, true, initial, updated,
error = updated - true, error_pct_of_range = 100 error / (upper - lower), and the run's
objective, n_evaluations and status. Failed runs have no updated values, so no rows.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from framework.core.errors import InputError


def tables(tables: dict[str, pd.DataFrame], parameters: dict | None = None) -> dict[str, pd.DataFrame]:
    if not isinstance(parameters, dict) or not parameters:
        raise InputError("report.truth.parameters: give the true value of at least one parameter, {name: value}")
    bad = {k: v for k, v in parameters.items() if isinstance(v, bool) or not isinstance(v, int | float)
           or not np.isfinite(v)}
    if bad:
        raise InputError(f"report.truth.parameters: true values must be finite numbers, got {bad}")
    params, runs = tables.get("parameters"), tables.get("runs")
    if params is None or params.empty or runs is None:
        return {"parameter_error": pd.DataFrame()}
    unknown = sorted(set(parameters) - set(params["parameter"]))
    if unknown:
        raise InputError(f"report.truth.parameters: {unknown} are not parameters of the study; "
                         f"known: {sorted(set(params['parameter']))}")
    run_cols = [c for c in ("run_id", "objective", "n_evaluations", "status") if c in runs]
    df = params[params["parameter"].isin(list(parameters))].merge(runs[run_cols], on="run_id", how="left")
    true = df["parameter"].map(parameters).astype(float)
    out = pd.DataFrame({
        "label": df["label"], "variant": df["variant"], "seed": df["seed"], "algorithm": df.get("algorithm"),
        "parameter": df["parameter"], "unit": df["unit"], "true": true, "initial": df["initial"],
        "updated": df["value"], "error": df["value"] - true,
        "error_pct_of_range": 100 * (df["value"] - true) / (df["upper"] - df["lower"]),
        "objective": df.get("objective"), "n_evaluations": df.get("n_evaluations"), "status": df.get("status"),
    })
    return {"parameter_error": out}


def figures(tables: dict[str, pd.DataFrame], out_dir: Path, parameters: dict | None = None) -> list[Path]:
    return []
