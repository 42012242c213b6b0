"""The README's bring-your-own-model example runs and recovers the true stiffnesses."""

import runpy
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("openseespy.opensees")


def test_own_model_example_updates_to_truth():
    ns = runpy.run_path(str(Path(__file__).resolve().parents[1] / "examples" / "own_model.py"))
    model, params = ns["model"], ns["params"]
    truth = model.modal({"k1_n_per_m": 2.6e6, "k2_n_per_m": 1.2e6})
    measured = ns["MeasuredModes"](truth.frequencies_hz, ("floor1", "floor2"), truth.shapes)
    problem = ns["UpdatingProblem"](model, measured)
    # no target: SM would stop once Pi < 1e-6 (the default target), short of the exact truth
    result = ns["run_optimizer"]("sm", problem, seed=0, budget=ns["Budget"](max_evaluations=200, target_objective=None))
    np.testing.assert_allclose(result.theta_best, [2.6e6, 1.2e6], rtol=1e-4)
    assert params.names == ["k1_n_per_m", "k2_n_per_m"]
