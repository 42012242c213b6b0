"""Parameter-selection analysis (SPEC 4): which settings converge, and how fast.

Two rules, side by side in the table:

- the source's absolute rule (columns ``*_absolute``): a setting converged when the mean
  best value of its runs fell below ``absolute_threshold`` = 1e-5 (its minimum being
  ~1.3e-6):   converged_absolute  <=>  mean_r(best_r) < 1e-5;
- the relative rule (ours; the minimum depends on the MAC convention): converged when the
  mean best value is within ``tolerance`` of the best value f* any method found
  (``reference_objective`` or the best run of the study):
      converged  <=>  mean_r(best_r) - f* < tolerance

Evaluations to converge: per run, the first evaluation whose best-so-far value is within
``tolerance`` of f* (absolute rule: below the threshold); averaged over the runs that got
there (``runs_reaching``, ``runs_reaching_absolute``).
Iterations to converge scale these by the run's iterations per evaluation.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd


def convergence_summary(runs: pd.DataFrame, history: pd.DataFrame, tolerance: float = 1e-5,
                        reference_objective: float | None = None,
                        absolute_threshold: float = 1e-5) -> pd.DataFrame:
    """One row per label and variant: mean best, converged (relative and absolute rule),
    evaluations/iterations to converge."""
    f_star = float(np.nanmin(runs["objective"]))
    if reference_objective is not None:
        f_star = min(f_star, float(reference_objective))
    threshold = f_star + tolerance
    reach = (history[history["best_objective"] <= threshold].groupby("run_id")["evaluation"].min())
    reach_abs = (history[history["best_objective"] < absolute_threshold].groupby("run_id")["evaluation"].min())
    runs = runs.assign(evals_to_converge=runs["run_id"].map(reach), evals_to_absolute=runs["run_id"].map(reach_abs))
    per_eval = runs["n_iterations"] / runs["n_evaluations"].where(runs["n_evaluations"] > 0)
    runs = runs.assign(iters_to_converge=runs["evals_to_converge"] * per_eval,
                       iters_to_absolute=runs["evals_to_absolute"] * per_eval)
    rows = []
    for (label, variant), g in runs.groupby(["label", "variant"], sort=False):
        mean_best = float(g["objective"].mean())
        converged = bool(mean_best - f_star < tolerance)
        converged_abs = bool(mean_best < absolute_threshold)
        rows.append({
            "label": label, "variant": variant, "runs": len(g), "mean_best": mean_best,
            "median_best": float(g["objective"].median()), "worst_best": float(g["objective"].max()),
            "f_star": f_star, "tolerance": tolerance, "converged": converged,
            "runs_reaching": int(g["evals_to_converge"].notna().sum()),
            "mean_evaluations_to_converge": float(g["evals_to_converge"].mean()),
            "mean_iterations_to_converge": float(g["iters_to_converge"].mean()),
            "mean_evaluations": float(g["n_evaluations"].mean()),
            "result": (f"{g['evals_to_converge'].mean():.0f} evaluations" if converged else "not converged"),
            "absolute_threshold": absolute_threshold, "converged_absolute": converged_abs,
            "runs_reaching_absolute": int(g["evals_to_absolute"].notna().sum()),
            "mean_evaluations_to_absolute": float(g["evals_to_absolute"].mean()),
            "mean_iterations_to_absolute": float(g["iters_to_absolute"].mean()),
            "result_absolute": (f"{g['evals_to_absolute'].mean():.0f} evaluations" if converged_abs
                                else "not converged"),
        })
    return pd.DataFrame(rows)


def tables(tables: dict[str, pd.DataFrame], tolerance: float = 1e-5,
           reference_objective: float | None = None, absolute_threshold: float = 1e-5,
           title: str = "") -> dict[str, pd.DataFrame]:
    """``convergence_summary`` from the runs and history tables."""
    if "runs" not in tables or "history" not in tables or tables["runs"].empty:
        return {}
    return {"convergence_summary": convergence_summary(tables["runs"], tables["history"], tolerance,
                                                       reference_objective, absolute_threshold)}


def figures(tables: dict[str, pd.DataFrame], out_dir: Path, title: str = "", **_) -> list[Path]:
    """selection.png from the convergence_summary table (:mod:`framework.report.figures.selection`)."""
    summary = tables.get("convergence_summary")
    if summary is None or summary.empty:
        return []
    from framework.report.figures.selection import selection_figure

    return [selection_figure(summary, Path(out_dir) / "selection.png", title or Path(out_dir).name)]
