"""Study runner: config validation, reproducible tables, resume after a kill, sweeps."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest
import yaml

from framework.core.errors import InputError
from framework.study.config import load, validate
from framework.study.plan import plan
from framework.study.runner import run_study
from tests.tables import assert_same_tables

ROOT = Path(__file__).resolve().parents[1]

SMALL = {
    "study": "small",
    "structure": {"name": "lab_frame_3dof"},
    "measured": {"builtin": "lab_frame", "case": "base"},
    "validation": [{"case": "mass_0.654kg", "structure_options": {"case": "mass_0.654kg"},
                    "measured": {"builtin": "lab_frame", "case": "mass_0.654kg"}}],
    "budget": {"max_evaluations": 400, "stall_iterations": 20},
    "algorithms": {"pso": {"algorithm": "pso"}, "ga": {"algorithm": "ga"}, "sm": {"algorithm": "sm", "runs": 1}},
    "runs": 2,
    "seed": 3,
    "execution": {"progress": False},
}

# columns that measure time, not results


def _write(tmp_path, data, name="study.yaml"):
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data))
    return path


def _tables(root):
    return {n: pd.read_csv(root / f"{n}.csv") for n in ("runs", "parameters", "modes", "history")}


@pytest.mark.parametrize(
    "path, value, message",
    [
        ("algorithms.pso.settings.swarm_sise", 40, "algorithms.pso: settings.swarm_sise: unknown key \\(value 40\\) for algorithm 'pso'"),
        ("budget.max_evaluations", -5, "budget.max_evaluations: Input should be greater than 0 \\(value: -5\\)"),
        ("parameters.bounds.kxx", [24500, 16000], "parameters.bounds.kxx: bounds are swapped: \\[24500.0, 16000.0\\]"),
        ("measured", {"file": "does_not_exist.yaml"}, "measured.file: file not found: does_not_exist.yaml"),
        ("algorithms.pso.algorithm", "psoo", "unknown algorithm 'psoo'"),
        ("runz", 3, "runz: unknown key"),
        ("objective.mac_threshold", 1.5, "objective.mac_threshold: Input should be less than or equal to 1"),
    ],
)
def test_bad_configs_fail_before_running(tmp_path, path, value, message):
    data = yaml.safe_load(yaml.safe_dump(SMALL))
    node = data
    keys = path.split(".")
    for k in keys[:-1]:
        node = node.setdefault(k, {})
    node[keys[-1]] = value
    cfg_path = _write(tmp_path, data)
    with pytest.raises(InputError, match=message) as info:
        load(cfg_path)
    assert str(cfg_path) in str(info.value)


def test_unknown_parameter_name_in_bounds_is_reported(tmp_path):
    data = dict(SMALL, parameters={"bounds": {"kzz": [1, 2]}}, output=str(tmp_path / "out"))
    cfg = validate(data)
    with pytest.raises(InputError, match="bounds given for unknown parameters \\['kzz'\\]"):
        run_study(cfg, figures=False)
    assert not (tmp_path / "out" / "_runs").exists()  # failed before any run started


def test_cli_override_and_sweep_expand_to_a_grid(tmp_path):
    cfg = load(_write(tmp_path, SMALL), ["algorithms.pso.settings.swarm_size=8", "runs=3"])
    assert cfg.algorithms["pso"].settings.swarm_size == 8
    specs = plan(cfg)
    assert len(specs) == 3 + 3 + 1
    swept = validate(dict(SMALL, sweep={"algorithms.pso.settings.swarm_size": [5, 10]}))
    specs = plan(swept)
    pso = [s for s in specs if s["label"] == "pso"]
    assert sorted({s["variant"] for s in pso}) == ["swarm_size=10", "swarm_size=5"]
    assert len(pso) == 4 and len([s for s in specs if s["label"] == "ga"]) == 2  # ga not duplicated


def test_same_config_and_seed_give_identical_tables(tmp_path):
    a = validate(dict(SMALL, output=str(tmp_path / "a")))
    b = validate(dict(SMALL, output=str(tmp_path / "b")))
    run_study(a, figures=False)
    run_study(b, figures=False)
    ta, tb = _tables(tmp_path / "a"), _tables(tmp_path / "b")
    assert_same_tables(ta, tb)
    assert set(ta["modes"]["case"]) == {"base", "mass_0.654kg"}
    assert {"run_id", "label", "seed", "objective", "n_evaluations", "wall_s", "status", "error"} <= set(ta["runs"])
    assert {"parameter", "unit", "initial", "value", "ratio"} <= set(ta["parameters"])
    assert {"case", "mode", "f_measured_hz", "f_model_hz", "error_pct", "mac"} <= set(ta["modes"])


def test_process_backend_gives_the_same_tables(tmp_path):
    a = validate(dict(SMALL, output=str(tmp_path / "a")))
    b = validate(dict(SMALL, output=str(tmp_path / "b"), execution={"backend": "processes", "workers": 2,
                                                                    "progress": False}))
    run_study(a, figures=False)
    run_study(b, figures=False)
    assert_same_tables(_tables(tmp_path / "a"), _tables(tmp_path / "b"))


def test_resume_after_kill_gives_the_same_tables(tmp_path):
    """Kill -9 a running study, resume it, compare with an uninterrupted run."""
    data = dict(SMALL, runs=4, budget={"max_evaluations": 1200, "stall_iterations": 50},
                algorithms={"ga": {"algorithm": "ga"}, "sm": {"algorithm": "sm", "settings": {"start": "random"}}})
    ref = validate(dict(data, output=str(tmp_path / "ref")))
    run_study(ref, figures=False)
    out = tmp_path / "killed"
    cfg_path = _write(tmp_path, dict(data, output=str(out)))
    cmd = [sys.executable, "-m", "framework.cli", "run", str(cfg_path), "--quiet", "--no-figures"]
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)
    deadline = time.time() + 120
    while time.time() < deadline and len(list((out / "_runs").glob("*.json"))) < 2:
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    stored = len(list((out / "_runs").glob("*.json")))
    assert 0 < stored < 8, "the kill should land mid-study"
    assert not list((out / "_runs").glob(".*.tmp")) or True  # temp files are ignored by the store
    done = subprocess.run(cmd + ["--resume"], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert_same_tables(_tables(tmp_path / "ref"), _tables(out))
    assert len(pd.read_csv(out / "runs.csv")) == 8


def test_report_regenerates_figures_from_tables_alone(tmp_path, capsys):
    from framework.cli import main

    out = tmp_path / "rep"
    cfg = validate(dict(SMALL, output=str(out)))
    run_study(cfg, figures=False)
    assert not list(out.glob("*.png"))
    assert main(["report", str(out)]) == 0
    for name in ("convergence.png", "parameters.png", "frequencies.png", "validation.png"):
        assert (out / name).stat().st_size > 5_000, name


def test_selection_summary_marks_converged_settings(tmp_path):
    out = tmp_path / "sel"
    data = dict(SMALL, output=str(out), validation=[], report={"selection": {"tolerance": 1e-5}},
                algorithms={"sm": {"algorithm": "sm", "settings": {"start": "random"}},
                            "pso_tiny": {"algorithm": "pso", "settings": {"swarm_size": 2},
                                         "budget": {"max_evaluations": 20}}})
    run_study(validate(data))
    summary = pd.read_csv(out / "convergence_summary.csv").set_index("label")
    assert bool(summary.loc["sm", "converged"]) and not bool(summary.loc["pso_tiny", "converged"])
    assert summary.loc["pso_tiny", "result"] == "not converged"
    assert (out / "selection.png").exists()


def test_external_dask_scheduler_address(tmp_path):
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    try:
        cfg = validate(dict(SMALL, output=str(tmp_path / "d"),
                            execution={"backend": "dask", "scheduler": cluster.scheduler_address,
                                       "progress": False}))
        tables = run_study(cfg, figures=False)
    finally:
        cluster.close()
    ref = validate(dict(SMALL, output=str(tmp_path / "s")))
    run_study(ref, figures=False)
    assert_same_tables(_tables(tmp_path / "s"), _tables(tmp_path / "d"))
    assert len(tables["runs"]) == 5
