"""Multi-start statistics next to another package's published multi-start results.

Asked for with ``report: {starts: {reach_rel_tol: 0.001, source: {<variant or label>: {...}}}}``
(studies/external_footbridge_eigenvector.yaml: the SMU package's 100 footbridge starts).
Every run of a label is one start. Table ``starts``, one row per (label, variant):

- ``runs``, ``best_objective``, ``median_objective``, ``mean_evaluations``,
  ``stopped_by_budget`` (runs with status "budget"), ``median_wall_s`` and ``mean_wall_s``
  per start (wall time of the run);
- ``reach_threshold`` = (1 + ``reach_rel_tol``) x ``reference_best``, the lower of our best
  and the source's best (so that both sides count starts against the same value);
  ``reached`` / ``reached_share``: our starts at or below it;
- the source's numbers as given (``source_name``, ``source_best_objective``,
  ``source_starts``, ``source_reached``, ``source_median_wall_s``; NaN where no source is
  given for the row) and ``best_rel_to_source`` = ours / source - 1 and
  ``wall_ratio_to_source`` = our median wall time / the source's (different machines).

The source entry is looked up by variant first, then by label. ``source_reached`` is the
source's own count at ``reach_rel_tol`` of its best; it is only comparable with ours while
our best is not below the source's by more than that tolerance (``reached_comparable``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

SOURCE_KEYS = {"best_objective", "starts", "reached", "median_wall_s", "name"}


def _check_source(source: dict) -> dict:
    for key, entry in source.items():
        if not isinstance(entry, dict):
            raise ValueError(f"report.starts.source.{key}: must be a mapping, got {entry!r}")
        unknown = sorted(set(entry) - SOURCE_KEYS)
        if unknown:
            raise ValueError(f"report.starts.source.{key}: unknown key(s) {unknown}; known: {sorted(SOURCE_KEYS)}")
        if "best_objective" not in entry:
            raise ValueError(f"report.starts.source.{key}: best_objective is required")
    return source


def starts_table(runs: pd.DataFrame, reach_rel_tol: float = 0.001, source: dict | None = None) -> pd.DataFrame:
    source = _check_source(source or {})
    ok = runs[runs["objective"].notna()]
    rows = []
    variants = ok["variant"] if "variant" in ok else pd.Series("default", index=ok.index)
    for (label, variant), g in ok.groupby([ok["label"], variants], sort=False):
        src = source.get(variant, source.get(label, {}))
        best = float(g["objective"].min())
        src_best = float(src.get("best_objective", np.nan))
        reference = min(best, src_best) if src else best
        threshold = reference * (1.0 + reach_rel_tol)
        reached = int((g["objective"] <= threshold).sum())
        src_starts = float(src.get("starts", np.nan))
        src_reached = float(src.get("reached", np.nan))
        src_wall = float(src.get("median_wall_s", np.nan))
        median_wall = float(g["wall_s"].median())
        rows.append({
            "label": label, "variant": variant, "runs": len(g),
            "best_objective": best, "median_objective": float(g["objective"].median()),
            "mean_evaluations": float(g["n_evaluations"].mean()),
            "stopped_by_budget": int((g["status"] == "budget").sum()) if "status" in g else 0,
            "median_wall_s": median_wall, "mean_wall_s": float(g["wall_s"].mean()),
            "reach_rel_tol": reach_rel_tol, "reference_best": reference, "reach_threshold": threshold,
            "reached": reached, "reached_share": reached / len(g),
            "source_name": src.get("name", ""), "source_best_objective": src_best,
            "source_starts": src_starts, "source_reached": src_reached,
            "source_reached_share": src_reached / src_starts if src_starts else np.nan,
            "source_median_wall_s": src_wall,
            "best_rel_to_source": best / src_best - 1.0,
            "reached_comparable": bool(src) and best >= src_best * (1.0 - reach_rel_tol),
            "wall_ratio_to_source": median_wall / src_wall,
        })
    return pd.DataFrame(rows)


def tables(tables: dict[str, pd.DataFrame], reach_rel_tol: float = 0.001, source: dict | None = None,
           **_) -> dict[str, pd.DataFrame]:
    if "runs" not in tables or tables["runs"].empty:
        return {}
    return {"starts": starts_table(tables["runs"], reach_rel_tol, source)}


def figures(tables: dict[str, pd.DataFrame], out_dir: Path, **_) -> list[Path]:
    return []
