"""Summary of an updating study with several starts and methods (the bridge study, SPEC 6),
from its tables only.

Asked for with ``report: {updating_summary: {starts: sm, spread: pso}}``. Tables:

- ``<starts>_starts`` (``sm_starts``): the runs of algorithm ``starts`` (e.g. SM from
  several start factors): ratio of every parameter, objective, evaluations, iterations,
  condition number, status, and ``max_ratio_distance_between_starts`` = max_j (max - min
  over runs of ratio_j): near 0 when every start reaches the same point; per ``method``
  when the runs have that setting (SM's trust region and pseudo-inverse iteration);
- ``<spread>_spread`` (``pso_spread``): per label of algorithm ``spread`` (e.g. the
  source's 200 generations and a stall-rule variant), count, mean, std, min, quartiles
  and max over the runs of every parameter ratio, of the objective, and of the
  evaluations and iterations;
- ``snt_minima``: the minima of every run that reports them (SNT): parameter ratios, raw
  and derated objective, ``artefact_of_niche_radius`` (the optimizer's flag), distances
  to the earlier minima, the niche radius r, and ``on_niche_boundary``: the nearest
  earlier minimum lies at r within 1 %. The derating G(d) = (d / r)^m is 1 from d = r on,
  so the derated surface has a rim there: a minimum on the rim is an artefact even when
  its raw and derated values agree;
- ``updated_modes_best_run``: the base-case modes of the run with the lowest objective;
- ``updated_modes_by_label``: the base-case modes of the best run of every label.

Figures (:mod:`framework.report.figures.updating_summary`): ``updated_ratios.png`` (ratio
per parameter, one point per run, by algorithm), ``updated_errors.png`` (frequency error per
mode, one point per run, lines at +-``error_band_pct``).

The minima's parameter vectors are in the problem's parameter order, which the sorted
parameters table does not keep: it is recovered from the run's own best point (the best
minimum), or given as ``parameter_order``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from framework.core.status import FAILURES

FAILED = FAILURES


def _ratios(runs: pd.DataFrame, parameters: pd.DataFrame) -> tuple[pd.DataFrame, list[str]]:
    """One row per run with the ratio of every parameter as a column."""
    names = list(dict.fromkeys(parameters["parameter"]))
    wide = parameters.pivot_table(index="run_id", columns="parameter", values="ratio")[names].reset_index()
    keep = [c for c in ("run_id", "label", "algorithm", "method", "seed", "objective", "n_evaluations",
                        "n_iterations", "condition_number", "status") if c in runs]
    return runs[keep].merge(wide, on="run_id"), names


def starts_table(wide: pd.DataFrame, names: list[str], algorithm: str) -> pd.DataFrame:
    sel = wide[wide["algorithm"] == algorithm].sort_values(["label", "seed"]).reset_index(drop=True)
    if sel.empty:
        return sel
    groups = sel["method"].fillna("") if "method" in sel else pd.Series("", index=sel.index)
    distance = {g: float(np.max(np.ptp(sel.loc[groups == g, names].to_numpy(float), axis=0))) for g in groups.unique()}
    return sel.assign(max_ratio_distance_between_starts=groups.map(distance))


def spread_table(wide: pd.DataFrame, names: list[str], algorithm: str) -> pd.DataFrame:
    sel = wide[wide["algorithm"] == algorithm]
    if sel.empty:
        return pd.DataFrame()
    counts = [c for c in ("n_evaluations", "n_iterations") if c in sel]
    parts = [g[names + ["objective"] + counts].astype(float).describe().T.reset_index(names="quantity")
             .assign(label=label) for label, g in sel.groupby("label", sort=True)]
    out = pd.concat(parts, ignore_index=True)
    return out[["label"] + [c for c in out.columns if c != "label"]]


def _order(run_params: pd.DataFrame, best_x: list[float], given: list[str] | None) -> list[str]:
    """Names in the problem's order: given, or matched through the run's best point."""
    if given:
        return list(given)
    x = run_params.set_index("parameter")["normalized"]
    order = []
    for value in best_x:
        hits = [n for n, v in x.items() if abs(v - value) <= 1e-12 and n not in order]
        if len(hits) != 1:
            raise ValueError("cannot tell the parameter order of the minima from the run's best point; "
                             "give report.updating_summary.parameter_order")
        order.append(hits[0])
    return order


def minima_table(extra: pd.DataFrame, parameters: pd.DataFrame, parameter_order: list[str] | None) -> pd.DataFrame:
    rows = []
    radius = {r.run_id: float(json.loads(r.value)) for r in extra[extra["key"] == "niche_radius"].itertuples()}
    for rec in extra[extra["key"] == "minima"].itertuples():
        minima = json.loads(rec.value)
        if not minima:
            continue
        run_params = parameters[parameters["run_id"] == rec.run_id]
        best = min(minima, key=lambda m: m["raw_objective"])
        names = _order(run_params, best["x"], parameter_order)
        initial = run_params.set_index("parameter")["initial"].reindex(names).to_numpy(float)
        r = radius.get(rec.run_id, np.nan)
        for m in minima:
            nearest = min(m["distance_to_previous"], default=np.nan)
            with np.errstate(divide="ignore", invalid="ignore"):
                ratios = np.where(initial != 0, np.asarray(m["theta"], float) / initial, np.nan)
            rows.append({
                "run_id": rec.run_id, "label": rec.label, "minimum": m["minimum"], **dict(zip(names, ratios)),
                "raw_objective": m["raw_objective"], "derated_objective": m["derated_objective"],
                "artefact_of_niche_radius": bool(m["artefact"]),
                "distance_to_previous": json.dumps([round(d, 4) for d in m["distance_to_previous"]]),
                "niche_radius": r, "on_niche_boundary": bool(abs(nearest - r) < 0.01 * r),
                "n_evaluations": m["n_evaluations"],
            })
    return pd.DataFrame(rows)


def tables(tables: dict[str, pd.DataFrame], starts: str = "sm", spread: str = "pso",
           parameter_order: list[str] | None = None, **_) -> dict[str, pd.DataFrame]:
    runs, parameters, modes = (tables.get(n) for n in ("runs", "parameters", "modes"))
    if runs is None or parameters is None or parameters.empty:
        return {}
    wide, names = _ratios(runs, parameters)
    out = {f"{starts}_starts": starts_table(wide, names, starts), f"{spread}_spread": spread_table(wide, names, spread)}
    extra = tables.get("extra")
    if extra is not None and not extra.empty:
        out["snt_minima"] = minima_table(extra, parameters, parameter_order)
    ok = runs[~runs["status"].isin(FAILED) & runs["objective"].notna()]
    if modes is not None and not ok.empty:
        best = ok.loc[ok["objective"].idxmin(), "run_id"]
        out["updated_modes_best_run"] = modes[(modes["run_id"] == best) & (modes["case"] == "base")].reset_index(
            drop=True)
        best_of = ok.loc[ok.groupby("label")["objective"].idxmin(), "run_id"]
        out["updated_modes_by_label"] = modes[modes["run_id"].isin(best_of) & (modes["case"] == "base")].sort_values(
            ["label", "mode"]).reset_index(drop=True)
    return {k: v for k, v in out.items() if not v.empty}


def figures(tables: dict[str, pd.DataFrame], out_dir: Path, error_band_pct: float = 3.0, **_) -> list[Path]:
    """updated_ratios.png and updated_errors.png from the runs that did not fail
    (:mod:`framework.report.figures.updating_summary`)."""
    from framework.report.figures.updating_summary import errors_figure, ratios_figure

    runs, parameters, modes = (tables.get(n) for n in ("runs", "parameters", "modes"))
    if runs is None or parameters is None or parameters.empty:
        return []
    out_dir = Path(out_dir)
    ok = runs[~runs["status"].isin(FAILED)]["run_id"]
    written = [ratios_figure(parameters[parameters["run_id"].isin(ok)], out_dir / "updated_ratios.png")]
    if modes is not None and not modes.empty:
        base = modes[(modes["case"] == "base") & modes["run_id"].isin(ok) & (modes["mode"] > 0)]
        written.append(errors_figure(base, out_dir / "updated_errors.png", error_band_pct))
    return written
