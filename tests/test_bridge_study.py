"""Bridge study tables: summary of optimizer runs, initial-frequency table."""

import json

import numpy as np
import pandas as pd
import pytest

from framework.models import bridge, bridge_study

NAMES = list(bridge.PARAMETER_NAMES)


def _fake_runner_tables(root):
    runs, params, modes, extra = [], [], [], []
    ratios = {
        "sm_1.00": [1.0, 1.1, 0.8, 0.76, 1.19, 1.3],
        "sm_0.92": [1.0, 1.1, 0.8, 0.77, 1.19, 1.3],
        "pso": [1.0, 1.1, 0.8, 0.76, 1.2, 1.29],
    }
    for k, (label, r) in enumerate(ratios.items()):
        run_id = f"r{k}"
        runs.append(
            {
                "run_id": run_id,
                "label": label,
                "seed": 0,
                "objective": 0.0023 + k * 1e-5,
                "n_evaluations": 70,
                "condition_number": 6.9,
                "status": "converged",
            }
        )
        for name, value in zip(NAMES, r):
            params.append({"run_id": run_id, "label": label, "seed": 0, "parameter": name, "ratio": value})
        for j in range(8):
            modes.append(
                {"run_id": run_id, "label": label, "case": "base", "mode": j + 1, "error_pct": 1.0, "mac": 0.999}
            )
    minima = [
        {
            "minimum": 1,
            "theta": [1.0] * 6,
            "raw_objective": 0.0023,
            "derated_objective": 0.0023,
            "artefact": False,
            "distance_to_previous": [],
            "n_evaluations": 900,
        },
        {
            "minimum": 2,
            "theta": [0.9] * 6,
            "raw_objective": 0.01,
            "derated_objective": 0.02,
            "artefact": True,
            "distance_to_previous": [0.5],
            "n_evaluations": 800,
        },
    ]
    extra.append({"run_id": "r9", "key": "minima", "value": json.dumps(minima)})
    extra.append({"run_id": "r9", "key": "niche_radius", "value": json.dumps(0.5)})
    for name, rows in (("runs", runs), ("parameters", params), ("modes", modes), ("extra", extra)):
        pd.DataFrame(rows).to_csv(root / f"{name}.csv", index=False)


def test_summarize_updating_reports_sm_spread_and_snt_minima(tmp_path):
    runs_dir = tmp_path / "updating"
    runs_dir.mkdir()
    _fake_runner_tables(runs_dir)
    out = bridge_study.summarize_updating(runs_dir, tmp_path)
    assert out["sm"]["max_ratio_distance_between_starts"].iloc[0] == pytest.approx(0.01)
    snt = out["snt"]
    assert list(snt["minimum"]) == [1, 2]
    assert snt["artefact_of_niche_radius"].tolist() == [False, True]
    assert snt["on_niche_boundary"].tolist() == [False, True]
    assert snt["K_y_deck"].iloc[1] == pytest.approx(0.9)
    assert (tmp_path / "snt_minima.csv").exists() and (tmp_path / "updated_ratios.png").exists()
    assert out["best_modes"]["run_id"].unique().tolist() == ["r0"]


def test_initial_frequency_table_shows_lost_mode_for_one_element(tmp_path):
    df = bridge_study.initial_frequencies(tmp_path, cable_elements=(1, 4))
    four = df[df.cable_elements == 4]
    assert np.all(np.abs(four.error_pct) < 11.0)
    one = df[(df.cable_elements == 1) & (df["mode"] == 2)]
    assert one.f_model_hz.iloc[0] > 2.5  # nearest vertical mode is the 2.78 Hz pylon mode
    assert (tmp_path / "initial_frequencies.png").exists()
