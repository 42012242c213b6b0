"""Distinct minima and method comparison of an updating study, from the tidy tables only.

Asked for with ``report: {minima: {x_tol: 0.05, bound_tol: 0.001}}`` (the external SMU
studies); ``gomu report results/external/<study>`` writes, next to the study's tables:

- ``summary.csv``: per method (label, variant): runs, best / median / worst objective,
  mean and total evaluations and wall time, runs within 1 % of the study's best value;
- ``bounds.csv``: per method and parameter, the share of runs whose final value lies at a
  bound (normalized coordinate within ``bound_tol`` of 0 or 1);
- ``minima.csv``: the distinct minima found: final points (and SNT minima) grouped by
  complete-linkage clustering in the normalized parameter box with the Chebyshev distance
  (two points belong to one minimum when every coordinate differs by < ``x_tol`` of its
  range), one row per minimum with its best objective, number of runs and methods, and
  the normalized coordinates (0 = lower, 1 = upper bound) of its best point;
- ``alphas.csv``: per method, the alpha values of the best run and the median over runs;
- figures ``objective_distribution.png``, ``cost.png``, ``distinct_minima.png``,
  ``alphas.png`` (:mod:`framework.report.figures.minima`).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pandas as pd


def _natural_key(name: str) -> tuple:
    """Sort key that puts alpha_2 before alpha_10."""
    return tuple(int(t) if t.isdigit() else t for t in re.split(r"(\d+)", name))


def parameter_names(parameters: pd.DataFrame) -> list[str]:
    """Parameter names in natural order (the stored table is sorted alphabetically)."""
    return sorted(dict.fromkeys(parameters["parameter"]), key=_natural_key)


def _method(df: pd.DataFrame) -> pd.Series:
    """Method label: the algorithm label, with the sweep variant when there is more than one."""
    if "variant" in df.columns and df["variant"].nunique() > 1:
        return df["label"] + " [" + df["variant"].astype(str) + "]"
    return df["label"]


def method_summary(runs: pd.DataFrame, near_rel: float = 0.01) -> pd.DataFrame:
    """Per method: best/median/worst objective, evaluations, wall time, runs near the best."""
    ok = runs[runs["status"] != "error"].assign(method=_method(runs))
    best = ok["objective"].min()
    g = ok.groupby("method", sort=False)
    out = pd.DataFrame(
        {
            "runs": g.size(),
            "objective_best": g["objective"].min(),
            "objective_median": g["objective"].median(),
            "objective_worst": g["objective"].max(),
            "evaluations_mean": g["n_evaluations"].mean(),
            "evaluations_total": g["n_evaluations"].sum(),
            "wall_s_mean": g["wall_s"].mean(),
            "wall_s_total": g["wall_s"].sum(),
            "runs_within_1pct_of_best": g["objective"].apply(lambda s: int((s <= best * (1 + near_rel)).sum())),
            "failed_evaluations": g["n_failed_evaluations"].sum() if "n_failed_evaluations" in ok else 0,
        }
    )
    errors = runs.assign(method=_method(runs)).groupby("method")["status"].apply(lambda s: int((s == "error").sum()))
    out["errors"] = errors.reindex(out.index).fillna(0).astype(int)
    return out.reset_index().sort_values("objective_best", kind="stable").reset_index(drop=True)


def at_bounds(parameters: pd.DataFrame, bound_tol: float = 1e-3) -> pd.DataFrame:
    """Per method and parameter: share of runs at the lower and at the upper bound."""
    df = parameters.assign(
        method=_method(parameters),
        at_lower=parameters["normalized"] <= bound_tol,
        at_upper=parameters["normalized"] >= 1.0 - bound_tol,
    )
    g = df.groupby(["method", "parameter"], sort=False)
    out = pd.DataFrame(
        {
            "runs": g.size(),
            "share_at_lower": g["at_lower"].mean(),
            "share_at_upper": g["at_upper"].mean(),
            "lower": g["lower"].first(),
            "upper": g["upper"].first(),
        }
    ).reset_index()
    per_run = df.groupby(["method", "run_id"])[["at_lower", "at_upper"]].sum().sum(axis=1)
    mean_at_bound = per_run.groupby("method").mean().rename("mean_parameters_at_bound_per_run")
    return out.merge(mean_at_bound, on="method")


def final_points(runs: pd.DataFrame, parameters: pd.DataFrame, extra: pd.DataFrame | None = None) -> pd.DataFrame:
    """One row per final point (run best, plus every SNT minimum): method, objective, x (normalized)."""
    names = parameter_names(parameters)
    wide = parameters.pivot_table(index="run_id", columns="parameter", values="normalized")[names]
    ok = runs[runs["status"] != "error"].assign(method=_method(runs)).set_index("run_id")
    rows = wide.join(ok[["method", "objective", "seed"]], how="inner").reset_index()
    rows["source"] = "run best"
    frames = [rows]
    if extra is not None and not extra.empty:
        minima = extra[extra["key"] == "minima"]
        recs = []
        for _, row in minima.iterrows():
            method = ok.loc[row["run_id"], "method"] if row["run_id"] in ok.index else row["label"]
            for rec in json.loads(row["value"]):
                recs.append(
                    {
                        "run_id": row["run_id"],
                        **dict(zip(names, rec["x"])),
                        "method": f"{method} minimum {rec['minimum']}",
                        "objective": rec["raw_objective"],
                        "seed": row["seed"],
                        "source": "snt minimum",
                    }
                )
        if recs:
            frames.append(pd.DataFrame(recs))
    return pd.concat(frames, ignore_index=True)


def distinct_minima(points: pd.DataFrame, names: list[str], x_tol: float = 0.05) -> tuple[pd.DataFrame, np.ndarray]:
    """Group final points into distinct minima (complete linkage, Chebyshev distance < x_tol).

    Returns (one row per minimum sorted by best objective, cluster id per point).
    """
    from scipy.cluster.hierarchy import fcluster, linkage

    X = points[names].to_numpy(float)
    if len(X) == 1:
        labels = np.ones(1, dtype=int)
    else:
        labels = fcluster(linkage(X, method="complete", metric="chebyshev"), t=x_tol, criterion="distance")
    rows = []
    for c in np.unique(labels):
        members = points[labels == c]
        best = members.loc[members["objective"].idxmin()]
        methods = sorted({m.split(" minimum ")[0] for m in members["method"]})
        rows.append(
            {
                "cluster": int(c),
                "objective_best": float(best["objective"]),
                "objective_max": float(members["objective"].max()),
                "n_points": len(members),
                "methods": ", ".join(methods),
                "best_method": best["method"],
                "best_seed": int(best["seed"]),
                **{n: float(best[n]) for n in names},
            }
        )
    table = pd.DataFrame(rows).sort_values("objective_best", kind="stable").reset_index(drop=True)
    order = {c: i + 1 for i, c in enumerate(table["cluster"])}
    table["minimum"] = table["cluster"].map(order)
    columns = ["minimum", *[c for c in table.columns if c not in ("cluster", "minimum")]]
    return table[columns], np.array([order[c] for c in labels])


def alpha_table(runs: pd.DataFrame, parameters: pd.DataFrame) -> pd.DataFrame:
    """Per method: alpha values of its best run and the median over its runs."""
    ok = runs[runs["status"] != "error"].assign(method=_method(runs))
    best_ids = ok.loc[ok.groupby("method")["objective"].idxmin(), ["method", "run_id", "objective"]]
    p = parameters.assign(method=_method(parameters))
    names = parameter_names(parameters)
    best = p[p["run_id"].isin(best_ids["run_id"])].pivot_table(index="method", columns="parameter", values="value")
    med = p.pivot_table(index="method", columns="parameter", values="value", aggfunc="median")
    out = pd.concat({"best": best[names], "median": med[names]}, names=["statistic"]).reset_index()
    return out.merge(best_ids.rename(columns={"objective": "best_objective"}), on="method")


# ---- driver -------------------------------------------------------------------------------
def tables(tables: dict[str, pd.DataFrame], x_tol: float = 0.05, bound_tol: float = 1e-3) -> dict[str, pd.DataFrame]:
    """summary, bounds, alphas and minima tables from the runs, parameters and extra tables."""
    runs, parameters = tables.get("runs"), tables.get("parameters")
    if runs is None or parameters is None or parameters.empty:
        return {}
    names = parameter_names(parameters)
    out = {
        "summary": method_summary(runs),
        "bounds": at_bounds(parameters, bound_tol),
        "alphas": alpha_table(runs, parameters),
    }
    points = final_points(runs, parameters, tables.get("extra"))
    out["minima"], _ = distinct_minima(points, names, x_tol)
    structure = runs["structure"].dropna().iloc[0] if "structure" in runs and runs["structure"].notna().any() else ""
    for df in out.values():
        df.insert(0, "structure", structure)
    return out


def figures(tables: dict[str, pd.DataFrame], out_dir: Path, **_) -> list[Path]:
    """objective_distribution.png, cost.png, distinct_minima.png, alphas.png from the tables
    (:mod:`framework.report.figures.minima`)."""
    from framework.report.figures.minima import minima_figures

    runs, parameters, minima = tables.get("runs"), tables.get("parameters"), tables.get("minima")
    if runs is None or parameters is None or minima is None:
        return []
    ok = runs[runs["status"] != "error"].assign(method=_method(runs))
    return minima_figures(ok, parameters.assign(method=_method(parameters)), minima, parameter_names(parameters),
                          Path(out_dir))
