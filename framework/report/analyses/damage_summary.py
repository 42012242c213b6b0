"""Damage-study tables and figures from the run tables of a ``damage`` study (SPEC 7).

Asked for with ``report: {damage_summary: {threshold: 0.05, figure_noise: [3.0]}}`` (the
``damage`` kind asks for it by default). Tables:

- ``comparison``: per noise_pct, measured_mesh, method, state: seeds, mean over seeds of
  the mean |error| of the estimated ratio, max |error| over elements and seeds, median of
  the per-seed max, false detections (undamaged elements with damage index above
  ``threshold``, summed over seeds), missed damaged elements, mean evaluations, mean Pi;
- ``damage_indices``: per noise_pct, measured_mesh, method, state, element: truth damage
  index 1 - r_true, mean and sd over seeds of the estimated damage index, share of seeds
  where the element is detected;
- ``lcurve_choice``: per noise_pct, measured_mesh, seed, state: the chosen tau (corner of
  maximum curvature), its residual and solution norms and curvature.

Figures (from these tables and the run tables only, :mod:`framework.report.figures.damage_summary`),
per noise level in ``figure_noise``: element ratios and damage indices per method, NSGA-II's
Pareto front and the L-curves of the first seed.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from framework.core.errors import InputError
from framework.damage.estimation import DETECTION_THRESHOLD as DEFAULT_THRESHOLD

GROUP = ["noise_pct", "measured_mesh", "method", "state"]


def _check(threshold) -> float:
    if isinstance(threshold, bool) or not isinstance(threshold, int | float) or not 0 < threshold < 1:
        raise InputError(f"report.damage_summary.threshold: give a number in (0, 1), got {threshold!r}")
    return float(threshold)


def check_options(threshold=DEFAULT_THRESHOLD, figure_noise=None) -> None:
    """InputError for a bad option (called when the config is read, before any run)."""
    _check(threshold)
    if figure_noise is not None and (not isinstance(figure_noise, list)
                                     or not all(isinstance(v, int | float) for v in figure_noise)):
        raise InputError(f"report.damage_summary.figure_noise: give a list of noise levels (%), got {figure_noise!r}")


def detections(elements: pd.DataFrame, threshold: float = DEFAULT_THRESHOLD) -> pd.DataFrame:
    """Elements with columns detected (damage index > threshold), truly_damaged (truth
    ratio < 1), false_detection and missed."""
    e = elements.copy()
    e["detected"] = e["damage_index"] > threshold
    e["truly_damaged"] = e["truth_ratio"] < 1.0 - 1e-12
    e["false_detection"] = e["detected"] & ~e["truly_damaged"]
    e["missed"] = ~e["detected"] & e["truly_damaged"]
    return e


def tables(tables: dict[str, pd.DataFrame], threshold: float = DEFAULT_THRESHOLD,
           figure_noise: list | None = None) -> dict[str, pd.DataFrame]:
    threshold = _check(threshold)
    states, elements = tables.get("states"), tables.get("elements")
    out: dict[str, pd.DataFrame] = {}
    if states is None or states.empty or elements is None or elements.empty:
        return {"comparison": pd.DataFrame(), "damage_indices": pd.DataFrame(), "lcurve_choice": pd.DataFrame()}
    e = detections(elements, threshold)
    per_run = e.groupby(["run_id", "method", "state"]).agg(n_false_detections=("false_detection", "sum"),
                                                           n_missed=("missed", "sum")).reset_index()
    s = states.merge(per_run, on=["run_id", "method", "state"], how="left")
    ok = s[s["status"] != "failed"]
    cmp = ok.groupby(GROUP).agg(
        seeds=("seed", "nunique"),
        mean_error=("mean_abs_error", "mean"),
        max_error=("max_abs_error", "max"),
        median_max_error=("max_abs_error", "median"),
        false_detections=("n_false_detections", "sum"),
        missed=("n_missed", "sum"),
        evaluations=("n_evaluations", "mean"),
        mean_objective=("objective", "mean"),
    ).reset_index()
    failed = s[s["status"] == "failed"].groupby(GROUP).size().rename("failed_runs").reset_index()
    cmp = cmp.merge(failed, on=GROUP, how="left").fillna({"failed_runs": 0})
    cmp["failed_runs"] = cmp["failed_runs"].astype(int)
    cmp["threshold"] = threshold
    out["comparison"] = cmp
    di = e.groupby([*GROUP, "element"]).agg(
        truth_damage_index=("truth_ratio", lambda v: float(1.0 - v.iloc[0])),
        mean_damage_index=("damage_index", "mean"),
        sd_damage_index=("damage_index", "std"),
        detection_rate=("detected", "mean"),
        seeds=("seed", "nunique"),
    ).reset_index()
    out["damage_indices"] = di
    lc = tables.get("lcurve")
    if lc is not None and not lc.empty:
        chosen = lc[lc["chosen"].astype(bool)]
        out["lcurve_choice"] = chosen[["noise_pct", "measured_mesh", "seed", "state", "tau", "residual_norm",
                                       "solution_norm", "curvature"]].sort_values(
            ["noise_pct", "measured_mesh", "state", "seed"]).reset_index(drop=True)
    else:
        out["lcurve_choice"] = pd.DataFrame()
    return out


def figures(tables: dict[str, pd.DataFrame], out_dir: Path, threshold: float = DEFAULT_THRESHOLD,
            figure_noise: list | None = None) -> list[Path]:
    """Element ratios, damage indices, Pareto front and L-curves per noise level
    (:mod:`framework.report.figures.damage_summary`)."""
    from framework.report.figures.damage_summary import damage_figures

    threshold = _check(threshold)
    di = tables.get("damage_indices")
    if di is None or di.empty:
        return []
    levels = sorted(set(di["noise_pct"])) if figure_noise is None else [float(v) for v in figure_noise]
    return damage_figures(di, tables.get("pareto"), tables.get("lcurve"), Path(out_dir), threshold, levels)


def comparison_wide(comparison: pd.DataFrame, noise_pct: float, mesh: str = "truth") -> pd.DataFrame:
    """One row per method, both damaged states side by side (for write-ups)."""
    d = comparison[(comparison["noise_pct"] == noise_pct) & (comparison["measured_mesh"] == mesh)
                   & comparison["state"].isin(["state1", "state2"])]
    wide = d.pivot(index="method", columns="state", values=["mean_error", "max_error", "false_detections"])
    wide.columns = [f"{state}_{name}" for name, state in wide.columns]
    return wide.reset_index()


