"""Wall time per run of each algorithm next to the source's (SPEC 4 timing comparison).

One row per label: runs, mean evaluations, mean and min wall time per run (s), wall time
scaled to 50 000 evaluations (wall_s x 50 000 / n_evaluations), time per evaluation (ms),
and the source's time for the algorithm (``source_wall_s``, keyed by algorithm name; the
"(ours)" labels show the source's time of their algorithm for comparison).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd


def timing_table(runs: pd.DataFrame, source_wall_s: dict[str, float] | None = None,
                 evaluations: int = 50_000) -> pd.DataFrame:
    source_wall_s = source_wall_s or {}
    rows = []
    for label, g in runs.groupby("label", sort=False):
        algorithm = str(g["algorithm"].iloc[0])
        per_eval = g["wall_s"] / g["n_evaluations"]
        rows.append({
            "label": label, "algorithm": algorithm, "runs": len(g),
            "mean_evaluations": float(g["n_evaluations"].mean()),
            "mean_wall_s": float(g["wall_s"].mean()), "min_wall_s": float(g["wall_s"].min()),
            "wall_s_per_50000": float((per_eval * evaluations).mean()),
            "ms_per_evaluation": float(per_eval.mean() * 1e3),
            "source_wall_s": float(source_wall_s.get(algorithm, np.nan)),
            "mean_best_objective": float(g["objective"].mean()),
        })
    out = pd.DataFrame(rows)
    out["ratio_to_source"] = out["wall_s_per_50000"] / out["source_wall_s"]
    return out


def tables(tables: dict[str, pd.DataFrame], source_wall_s: dict[str, float] | None = None,
           **_) -> dict[str, pd.DataFrame]:
    if "runs" not in tables or tables["runs"].empty:
        return {}
    return {"timing": timing_table(tables["runs"], source_wall_s)}


def figures(tables: dict[str, pd.DataFrame], out_dir: Path, **_) -> list[Path]:
    return []
