"""The best run of each model (variant or sweep value) side by side, from an updating study's
tables: updated parameters, updated frequencies and the predictions of the validation cases.

Asked for with ``report: {comparison: {}}`` (e.g. studies/lab_frame_detailed.yaml: the
detailed frame against the 3-DOF model; studies/lab_frame_detailed_inset.yaml: one model per
``column_inset_m``). A model is a group of runs with the same values of the columns ``by``
(default: the variant); its best run is the one with the lowest objective among the runs
that did not fail. Tables:

- ``comparison_runs``: one row per model: the settings that tell the models apart (e.g.
  structure, a swept option), its best run (label, seed, run_id, objective, n_evaluations,
  status), the number of runs and the updated value of every parameter (one column each);
- ``comparison``: model x case x mode of the best runs: f_measured_hz, f_model_hz,
  error_pct, mac, matched;
- ``comparison_summary``: model x case: modes, matched modes, max |error_pct|, min MAC.

Figure ``comparison.png``: frequency error per mode, one bar per model, one panel per case.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from framework.core.status import FAILURES

FAILED = FAILURES


def _model_names(df: pd.DataFrame, by: list[str]) -> pd.Series:
    return df[by].astype(str).agg(", ".join, axis=1) if len(by) > 1 else df[by[0]].astype(str)


#: columns of the runs table that are results or bookkeeping, not settings of a model
RESULT_COLUMNS = {"run_id", "study", "kind", "label", "seed", "objective", "n_evaluations", "n_iterations", "wall_s",
                  "status", "error", "n_failed_evaluations", "failures", "message", "condition_number", "traceback"}


def setting_columns(runs: pd.DataFrame, groups: pd.Series) -> list[str]:
    """Setting columns that tell the groups apart: one value within each group, several overall."""
    out = []
    for c in runs.columns:
        if c in RESULT_COLUMNS or runs[c].nunique(dropna=False) < 2:
            continue
        if (runs.groupby(groups)[c].nunique(dropna=False) <= 1).all():
            out.append(c)
    return out


def best_runs(runs: pd.DataFrame, by: list[str]) -> pd.DataFrame:
    """The lowest-objective run of each group of ``runs`` (failed runs left out), with the
    setting columns that tell the groups apart (e.g. structure, a swept option)."""
    ok = runs[~runs["status"].isin(FAILED) & runs["objective"].notna()]
    ok = ok.assign(model=_model_names(ok, by))
    best = ok.loc[ok.groupby("model", sort=False)["objective"].idxmin()]
    counts = ok.groupby("model", sort=False).size().rename("runs")
    keep = ["model", *by, *setting_columns(ok.drop(columns="model"), ok["model"]), "label", "seed", "run_id",
            "objective", "n_evaluations", "status"]
    return best[list(dict.fromkeys(keep))].merge(counts, on="model").reset_index(drop=True)


def comparison_tables(runs: pd.DataFrame, parameters: pd.DataFrame, modes: pd.DataFrame,
                      by: list[str]) -> dict[str, pd.DataFrame]:
    best = best_runs(runs, by)
    model_of = best.set_index("run_id")["model"]
    values = parameters[parameters["run_id"].isin(model_of.index)].pivot_table(
        index="run_id", columns="parameter", values="value", sort=False)
    best_runs_table = best.merge(values, left_on="run_id", right_index=True, how="left")
    cols = ["case", "mode", "mode_label", "f_measured_hz", "f_model_hz", "error_pct", "mac", "matched"]
    sel = modes[modes["run_id"].isin(model_of.index) & (modes["mode"] > 0)]
    table = sel.assign(model=sel["run_id"].map(model_of))[["model", *[c for c in cols if c in sel]]]
    order = {m: i for i, m in enumerate(best["model"])}
    cases = {c: i for i, c in enumerate(dict.fromkeys(["base", *table["case"]]))}
    table = table.sort_values(["case", "model", "mode"], key=lambda s: s.map(order) if s.name == "model" else (
        s.map(cases) if s.name == "case" else s), kind="stable").reset_index(drop=True)
    summary = table.groupby(["model", "case"], sort=False).agg(
        modes=("mode", "size"), matched=("matched", "sum"),
        max_abs_error_pct=("error_pct", lambda s: float(np.nanmax(np.abs(s))) if s.notna().any() else np.nan),
        min_mac=("mac", "min")).reset_index()
    summary["matched"] = summary["matched"].astype(int)
    return {"comparison_runs": best_runs_table, "comparison": table, "comparison_summary": summary}


def tables(tables: dict[str, pd.DataFrame], by: list[str] | str = "variant") -> dict[str, pd.DataFrame]:
    """comparison_runs, comparison and comparison_summary from the runs, parameters and modes."""
    by = [by] if isinstance(by, str) else list(by)
    runs, parameters, modes = (tables.get(n) for n in ("runs", "parameters", "modes"))
    if runs is None or parameters is None or modes is None or runs.empty or modes.empty:
        return {}
    missing = [c for c in by if c not in runs]
    if missing:
        raise ValueError(f"report.comparison.by: no column {missing} in the runs table")
    return comparison_tables(runs, parameters, modes, by)


def figures(tables: dict[str, pd.DataFrame], out_dir: Path, **_) -> list[Path]:
    """comparison.png from the comparison table (:mod:`framework.report.figures.comparison`)."""
    from framework.report.figures.comparison import comparison_figure

    table = tables.get("comparison")
    if table is None or table.empty:
        return []
    return [comparison_figure(table, Path(out_dir) / "comparison.png")]
