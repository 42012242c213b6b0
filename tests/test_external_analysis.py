"""Analysis of external-benchmark results on synthetic tidy tables (no SMU data needed)."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from framework.report.analyses import minima as minima_analysis
from framework.report.analyses.minima import distinct_minima, final_points, method_summary

NAMES = ["alpha_1", "alpha_2", "alpha_3"]


def _tables():
    """Two methods x 3 runs; runs end at two distinct minima A (x = 0.2, 0.8, 0.0) and B."""
    A, B = np.array([0.2, 0.8, 0.0]), np.array([0.7, 0.1, 1.0])
    finals = {
        ("sm", 0): (A, 1.0),
        ("sm", 1): (A + 0.01, 1.02),
        ("sm", 2): (B, 5.0),
        ("pso", 0): (B + 0.02, 5.1),
        ("pso", 1): (A - 0.01, 1.01),
        ("pso", 2): (B, 5.0),
    }
    runs, params = [], []
    for (label, seed), (x, obj) in finals.items():
        rid = f"{label}{seed}"
        runs.append(
            {
                "run_id": rid,
                "label": label,
                "variant": "default",
                "seed": seed,
                "algorithm": label,
                "objective": obj,
                "n_evaluations": 100 if label == "sm" else 800,
                "wall_s": 1.0,
                "status": "converged",
                "n_failed_evaluations": 0,
            }
        )
        for name, xi in zip(NAMES, np.clip(x, 0, 1)):
            params.append(
                {
                    "run_id": rid,
                    "label": label,
                    "variant": "default",
                    "seed": seed,
                    "parameter": name,
                    "lower": -1.0,
                    "upper": 1.0,
                    "normalized": xi,
                    "value": -1.0 + 2.0 * xi,
                }
            )
    extra = [
        {
            "run_id": "pso1",
            "label": "pso",
            "variant": "default",
            "seed": 1,
            "key": "minima",
            "value": json.dumps([{"minimum": 1, "x": [0.5, 0.5, 0.5], "raw_objective": 3.0}]),
        }
    ]
    return pd.DataFrame(runs), pd.DataFrame(params), pd.DataFrame(extra)


def test_summary_minima_and_bounds(tmp_path):
    runs, params, extra = _tables()
    summary = method_summary(runs)
    assert summary["method"].tolist() == ["sm", "pso"]  # sorted by best objective
    assert summary.loc[0, "objective_best"] == 1.0
    assert summary.set_index("method").loc["pso", "runs_within_1pct_of_best"] == 1  # 1.01 <= 1.01
    points = final_points(runs, params, extra)
    assert len(points) == 7 and (points["source"] == "snt minimum").sum() == 1
    minima, labels = distinct_minima(points, NAMES, x_tol=0.05)
    assert minima["objective_best"].tolist() == [1.0, 3.0, 5.0]
    assert minima["n_points"].tolist() == [3, 1, 3]
    assert minima.loc[0, "methods"] == "pso, sm"
    assert labels.tolist().count(1) == 3
    tables = {"runs": runs, "parameters": params, "extra": extra}
    out = minima_analysis.tables(tables)
    bounds = out["bounds"].set_index(["method", "parameter"])
    assert bounds.loc[("sm", "alpha_3"), "share_at_lower"] == pytest.approx(1 / 3)  # x = 0, 0.01 (not at it), 1
    assert bounds.loc[("sm", "alpha_3"), "share_at_upper"] == pytest.approx(1 / 3)
    alphas = out["alphas"].set_index(["statistic", "method"])
    assert alphas.loc[("best", "sm"), "alpha_1"] == pytest.approx(-0.6)
    files = minima_analysis.figures({**tables, **out}, tmp_path)
    assert {f.name for f in files} >= {"objective_distribution.png", "distinct_minima.png"}
    for f in files:
        assert f.stat().st_size > 0
