"""Smoke run of the beam damage study (tiny budgets): tables, columns and figures."""

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pandas as pd

STUDY = Path(__file__).resolve().parents[1] / "studies" / "beam_damage.py"


def _study_module():
    spec = importlib.util.spec_from_file_location("beam_damage_study", STUDY)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses resolve annotations through sys.modules
    spec.loader.exec_module(module)
    return module


def test_quick_study_writes_tidy_tables_and_figures(tmp_path):
    study = _study_module()
    settings = study.quick_settings(str(tmp_path))
    settings.noise_pct = (3.0,)
    frames = study.run_study(settings)
    runs, elements = frames["runs"], frames["elements"]
    methods = {"sm", "pso", "pso+sm", "nsga2", "nsga2+sm", "pso_tikhonov"}
    assert set(runs.method) == methods and set(runs.state) == {"state1", "state2"}
    assert len(elements) == len(runs) * 10
    assert set(elements.detected) <= {"yes", "no"}
    # the truth of the damaged element and the error column are consistent
    e6 = elements[(elements.state == "state2") & (elements.element == 6)]
    np.testing.assert_allclose(e6.truth, 0.85)
    np.testing.assert_allclose(e6.error, e6.updated_ratio - 0.85)
    # least-squares polish never leaves a worse objective than the global search it starts from
    obj = runs.set_index(["state", "method"]).objective
    for state in ("state1", "state2"):
        assert obj[(state, "pso+sm")] <= obj[(state, "pso")]
        assert obj[(state, "nsga2+sm")] <= obj[(state, "nsga2")]
    lcurve = pd.read_csv(tmp_path / "lcurve.csv")
    assert lcurve.groupby("state").chosen.sum().eq(1).all()
    assert (runs[runs.method == "pso_tikhonov"].tau > 0).all()
    pareto = pd.read_csv(tmp_path / "pareto.csv")
    assert pareto.chosen.sum() == 1
    for name in ("element_ratios", "damage_index", "pareto", "lcurve"):
        assert (tmp_path / f"{name}_noise3.png").stat().st_size > 10_000
    summary = pd.read_csv(tmp_path / "summary.csv")
    assert {"mean_abs_error", "max_abs_error", "false_detections"} <= set(summary.columns)
