"""The fast-path footbridge study config: its plan, and a clean stop without the SMU data."""

import os
import subprocess
import sys
from pathlib import Path

from framework.study.config import load
from framework.study.plan import plan

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "studies" / "external_footbridge_fast.yaml"


def test_plan_compares_the_fast_paths_with_todays_path_on_the_same_starts():
    specs = plan(load(CONFIG))
    by_label: dict[str, list] = {}
    for spec in specs:
        by_label.setdefault(spec["label"], []).append(spec)
    assert {k: len(v) for k, v in by_label.items()} == {
        "multistart_sm (ours)": 1, "hybrid_screening_sm (ours)": 10, "sm": 10, "sm_fd": 10}
    assert {s["variant"] for s in by_label["sm_fd"]} == {"today"}
    assert [s["seed"] for s in by_label["sm"]] == [s["seed"] for s in by_label["sm_fd"]] == list(range(10))
    fast = by_label["sm"][0]["task"]
    today = by_label["sm_fd"][0]["task"]
    assert fast["structure"]["options"]["solver"] == "shift_invert_ldl"
    assert today["structure"]["options"]["solver"] == "shift_invert"
    assert all(s["task"]["budget"]["max_evaluations"] == 3000 for s in by_label["hybrid_screening_sm (ours)"])


def test_study_without_the_smu_data_stops_with_one_line(tmp_path):
    env = {**os.environ, "GOMU_SMU_DIR": str(tmp_path), "PYTHONPATH": str(ROOT)}
    out = subprocess.run([sys.executable, "-m", "framework.cli", "run", str(CONFIG), "--set",
                          f"output={tmp_path / 'out'}"], capture_output=True, text=True, env=env, timeout=120)
    assert out.returncode == 2
    assert "SMU benchmark file not found" in out.stderr and "steel_footbridge_model.mat" in out.stderr
    assert "Traceback" not in out.stderr and len(out.stderr.strip().splitlines()) == 1
