"""Robustness (issue 10): bad input, failed analyses, dead workers, kills, determinism."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from framework.cli import main
from framework.core.errors import InputError
from framework.measured import modes as measurements
from framework.study.config import validate
from framework.study.runner import run_study

ROOT = Path(__file__).resolve().parents[1]
TESTS = Path(__file__).resolve().parent

BASE = {
    "study": "robust",
    "structure": {"name": "lab_frame_3dof"},
    "measured": {"builtin": "lab_frame", "case": "base"},
    "budget": {"max_evaluations": 300, "stall_iterations": 20},
    "algorithms": {"sm": {"algorithm": "sm", "settings": {"start": "random"}}, "pso": {"algorithm": "pso"}},
    "runs": 2,
    "execution": {"progress": False},
}

GOOD_DATA = "dofs: [y, x, torsion]\nmodes:\n  - {frequency_hz: 3.58, shape: [1.0, 0.004, -0.01]}\n"


def _config_with(tmp_path, changes: dict, data_text: str | None = None, data_name: str = "data.yaml"):
    data = yaml.safe_load(yaml.safe_dump(BASE))
    if data_text is not None:
        (tmp_path / data_name).write_text(data_text)
        data["measured"] = {"file": data_name}
    for path, value in changes.items():
        node = data
        keys = path.split(".")
        for k in keys[:-1]:
            node = node.setdefault(k, {})
        if value is _DELETE:
            node.pop(keys[-1], None)
        else:
            node[keys[-1]] = value
    cfg = tmp_path / "study.yaml"
    cfg.write_text(yaml.safe_dump(data))
    return cfg


_DELETE = object()

# (id, config changes, data file text or None, expected message regex)
BAD_INPUTS = [
    ("typo_top_key", {"runz": 3}, None, r"runz: unknown key"),
    ("typo_nested_key", {"objective.alpah": 1.0}, None, r"objective.alpah: unknown key"),
    ("unknown_algorithm", {"algorithms.pso.algorithm": "psoo"}, None, r"unknown algorithm 'psoo'"),
    ("unknown_setting", {"algorithms.pso.settings": {"swarmsize": 3}}, None, r"settings.swarmsize: unknown key"),
    ("non_numeric_setting", {"algorithms.pso.settings": {"swarm_size": "many"}}, None,
     r"settings.swarm_size: Input should be a valid integer.*'many'"),
    ("negative_budget", {"budget.max_evaluations": -1}, None, r"budget.max_evaluations: Input should be greater than 0"),
    ("swapped_bounds", {"parameters.bounds": {"kxx": [24500, 16000]}}, None, r"parameters.bounds.kxx: bounds are swapped"),
    ("empty_bounds", {"parameters.bounds": {"kxx": [20000, 20000]}}, None, r"parameters.bounds.kxx: bounds are empty"),
    ("initial_outside_bounds", {"parameters.bounds": {"kxx": [21000, 24000]}}, None,
     r"parameter 'kxx': initial=20294.0 is outside bounds \[21000.0, 24000.0\]"),
    ("non_numeric_bound", {"parameters.bounds": {"kxx": ["low", 2]}}, None, r"parameters.bounds.kxx.0: Input should be a valid number"),
    ("infinite_bound", {"parameters.bounds": {"kxx": [0, ".inf"]}}, None, r"parameters.bounds.kxx"),
    ("missing_data_file", {"measured": {"file": "nope.yaml"}}, None, r"measured.file: file not found: nope.yaml"),
    ("builtin_and_file", {"measured": {"builtin": "lab_frame", "file": "x.yaml"}}, None, r"give exactly one of 'builtin' or 'file'"),
    ("unknown_builtin", {"measured": {"builtin": "lab_frams"}}, None, r"measured.builtin='lab_frams' unknown"),
    ("unknown_structure", {"structure.name": "lab_frame_4dof"}, None, r"structure.name='lab_frame_4dof'"),
    ("unknown_case", {"measured": {"builtin": "lab_frame", "case": "mass_9kg"}}, None, r"unknown measured case 'mass_9kg'"),
    ("zero_runs", {"runs": 0}, None, r"runs: Input should be greater than or equal to 1"),
    ("no_algorithms", {"algorithms": {}}, None, r"algorithms: .*at least one algorithm is required"),
    ("empty_sweep", {"sweep": {"algorithms.pso.settings.swarm_size": []}}, None, r"sweep 'algorithms.pso.settings.swarm_size' has no values"),
    ("unknown_parameter_name", {"parameters.names": ["kxx", "kzz"]}, None, r"no parameter named 'kzz'"),
    ("mac_threshold_above_1", {"objective.mac_threshold": 1.5}, None, r"objective.mac_threshold: Input should be less than or equal to 1"),
    ("ratio_constraint_unknown", {"objective.ratio_constraints": [{"numerator": "kxx", "denominator": "kq"}]}, None,
     r"ratio_constraints: parameter 'kq' is not updated"),
    ("unknown_structure_option", {"structure.options": {"stifness": 2}}, None, r"structure 'lab_frame_3dof': bad options \['stifness'\]"),
    ("missing_study_name", {"study": _DELETE}, None, r"study: Field required"),
    ("nan_frequency", {}, "dofs: [y]\nmodes:\n  - {frequency_hz: .nan}\n", r"frequency_hz: must be a finite positive number, got nan"),
    ("negative_frequency", {}, "dofs: [y]\nmodes:\n  - {frequency_hz: -1.0}\n", r"must be a finite positive number, got -1.0"),
    ("string_frequency", {}, "dofs: [y]\nmodes:\n  - {frequency_hz: fast}\n", r"frequency_hz: not a number: 'fast'"),
    ("shape_wrong_length", {}, "dofs: [y, x, torsion]\nmodes:\n  - {frequency_hz: 3.5, shape: [1.0, 0.0]}\n",
     r"shape: has 2 values, expected 3 \(one per DOF\)"),
    ("duplicate_dofs", {}, "dofs: [y, y]\nmodes:\n  - {frequency_hz: 3.5, shape: [1.0, 0.0]}\n", r"duplicate DOF labels \['y'\]"),
    ("unknown_dof_label", {}, "dofs: [y, z]\nmodes:\n  - {frequency_hz: 3.5, shape: [1.0, 0.1]}\n",
     r"measured DOF\(s\) \['z'\] are not DOFs of model"),
    ("empty_data_file", {}, "", r"file is empty"),
    ("wrong_units", {}, "units: {frequency: rad/s}\n" + GOOD_DATA, r"units.frequency: unsupported unit 'rad/s'"),
    ("zero_shape", {}, "dofs: [y]\nmodes:\n  - {frequency_hz: 3.5, shape: [0.0]}\n", r"mode 1 shape is all zeros"),
    ("data_unknown_key", {}, "dofs: [y]\nmodes:\n  - {frequency: 3.5}\n", r"unknown key\(s\) \['frequency'\]"),
    ("csv_unknown_column", {}, "frequency_hz,freq2\n3.5,1\n", r"unknown column\(s\) \['freq2'\]"),
    ("csv_non_numeric", {}, "frequency_hz,damping_ratio\n3.5,low\n", r"column 'damping_ratio': not numeric: 'low'"),
    ("data_not_yaml", {}, "modes: [1, 2\n", r"not valid YAML"),
]


def _data_name(case_id):
    return "data.csv" if case_id.startswith("csv_") else "data.yaml"


@pytest.mark.parametrize("case_id, changes, data_text, message", BAD_INPUTS, ids=[b[0] for b in BAD_INPUTS])
def test_bad_input_fails_early_with_a_named_message(tmp_path, capsys, case_id, changes, data_text, message):
    cfg = _config_with(tmp_path, changes, data_text, _data_name(case_id))
    code = main(["validate", str(cfg)])  # any exception other than InputError would fail the test
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("gomu: error: ")
    assert __import__("re").search(message, err), err
    assert "Traceback" not in err
    # and the same config never starts a run
    code = main(["run", str(cfg), "--quiet", "--no-figures"])
    assert code == 2
    assert not (ROOT / "results" / "robust").exists()


def test_at_least_30_distinct_bad_inputs():
    assert len({b[0] for b in BAD_INPUTS}) >= 30


def test_missing_and_empty_config_files(tmp_path, capsys):
    assert main(["validate", str(tmp_path / "none.yaml")]) == 2
    assert "config file not found" in capsys.readouterr().err
    (tmp_path / "e.yaml").write_text("")
    assert main(["validate", str(tmp_path / "e.yaml")]) == 2
    assert "config file is empty" in capsys.readouterr().err
    (tmp_path / "ok.yaml").write_text(yaml.safe_dump(BASE))
    assert main(["run", str(tmp_path / "ok.yaml"), "--set", "runs"]) == 2
    assert "expected KEY.PATH=VALUE" in capsys.readouterr().err


def test_cli_error_has_no_traceback_in_a_real_process(tmp_path):
    cfg = _config_with(tmp_path, {"budget.max_evaluations": -1})
    done = subprocess.run([sys.executable, "-m", "framework.cli", "validate", str(cfg)], cwd=ROOT,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 2
    assert "budget.max_evaluations" in done.stderr and "Traceback" not in done.stderr


# ---- failed analyses ------------------------------------------------------------------------
def test_failed_evaluations_are_recorded_and_the_study_goes_on(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(TESTS))
    cfg = validate(dict(BASE, structure={"name": "fault_models:make_holey"}, output=str(tmp_path / "out"),
                        algorithms={"pso": {"algorithm": "pso"}}))
    runs = run_study(cfg, figures=False)["runs"]
    assert len(runs) == 2 and (runs["status"] != "error").all()
    assert (runs["n_failed_evaluations"] > 0).all()
    assert runs["failures"].str.contains("not_converged x").all()
    params = pd.read_csv(tmp_path / "out" / "parameters.csv")
    assert (params.loc[params.parameter == "kxx", "value"] <= 22000.0).all()  # never a failed point as best


def test_a_dead_run_worker_is_replaced_and_its_run_redone(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(TESTS))
    marker = tmp_path / "died"
    common = dict(BASE, algorithms={"sm": {"algorithm": "sm", "settings": {"start": "random"}}})
    cfg = validate(dict(common, structure={"name": "fault_models:make_dying", "options": {"marker": str(marker)}},
                        output=str(tmp_path / "out"), execution={"backend": "processes", "workers": 2,
                                                                 "progress": False}))
    runs = run_study(cfg, figures=False)["runs"]
    assert marker.exists()  # a worker really died
    assert len(runs) == 2 and (runs["status"] != "error").all()
    ref = validate(dict(common, output=str(tmp_path / "ref")))
    ref_runs = run_study(ref, figures=False)["runs"]
    np.testing.assert_array_equal(runs["objective"], ref_runs["objective"])


def test_a_dead_evaluation_worker_is_replaced(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(TESTS))
    import fault_models

    from framework.execution.parallel import ProcessRunner
    from framework.structures.lab_frame.model import measured
    from framework.updating.problem import UpdatingProblem

    runner = ProcessRunner(2)
    try:
        p = UpdatingProblem(fault_models.make_dying(str(tmp_path / "m")), measured())
        X = np.random.default_rng(0).random((6, 6))
        values = p.objective(X, runner)
    finally:
        runner.close()
    ref = UpdatingProblem(fault_models.ThreeDofFrame(), measured()).objective(X)
    np.testing.assert_allclose(values, ref)


# ---- interruption -------------------------------------------------------------------------
KILL_STUDY = dict(BASE, runs=12, budget={"max_evaluations": 800, "stall_iterations": 30},
                  algorithms={"sm": {"algorithm": "sm", "settings": {"start": "random"}},
                              "ga": {"algorithm": "ga"}})


def _tables(root):
    return {n: pd.read_csv(root / f"{n}.csv").drop(columns=["wall_s"], errors="ignore")
            for n in ("runs", "parameters", "modes", "history")}


def test_repeated_kill_and_resume_gives_identical_tables(tmp_path):
    """Kill -9 the study at least 10 times at random moments, resume until done."""
    ref = validate(dict(KILL_STUDY, output=str(tmp_path / "ref")))
    run_study(ref, figures=False)
    out = tmp_path / "killed"
    cfg_path = tmp_path / "kill.yaml"
    cfg_path.write_text(yaml.safe_dump(dict(KILL_STUDY, output=str(out))))
    cmd = [sys.executable, "-m", "framework.cli", "run", str(cfg_path), "--quiet", "--no-figures", "--resume"]
    rng = np.random.default_rng(2024)
    kills = 0
    for _ in range(60):
        proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                start_new_session=True)
        before = len(list((out / "_runs").glob("*.json"))) if (out / "_runs").exists() else 0
        wait_until = time.time() + 60
        # wait for the next run to be stored, then kill at a random moment soon after
        while time.time() < wait_until and proc.poll() is None:
            now = len(list((out / "_runs").glob("*.json"))) if (out / "_runs").exists() else 0
            if now > before:
                break
            time.sleep(0.02)
        time.sleep(float(rng.uniform(0.0, 0.3)))
        if proc.poll() is not None:
            break
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        kills += 1
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert kills >= 10
    a, b = _tables(tmp_path / "ref"), _tables(out)
    for name in a:
        pd.testing.assert_frame_equal(a[name], b[name], check_exact=True)
    assert len(b["runs"]) == 24 and b["runs"]["run_id"].is_unique
    assert not list(out.rglob("*.tmp"))  # no half-written files left behind


# ---- determinism --------------------------------------------------------------------------
def test_identical_tables_in_serial_process_and_dask_execution(tmp_path):
    pytest.importorskip("distributed")
    data = dict(BASE, algorithms={"pso": {"algorithm": "pso"}, "ga": {"algorithm": "ga"},
                                  "sm": {"algorithm": "sm", "settings": {"start": "random"}}})
    outs = {}
    for backend in ("serial", "processes", "dask"):
        cfg = validate(dict(data, output=str(tmp_path / backend),
                            execution={"backend": backend, "workers": 2, "progress": False}))
        run_study(cfg, figures=False)
        outs[backend] = _tables(tmp_path / backend)
    for backend in ("processes", "dask"):
        for name in outs["serial"]:
            pd.testing.assert_frame_equal(outs["serial"][name], outs[backend][name], check_exact=True)


def test_population_evaluation_on_dask_and_processes_matches_serial(tmp_path):
    pytest.importorskip("distributed")
    data = dict(BASE, algorithms={"pso": {"algorithm": "pso"}}, runs=1)
    outs = {}
    for evaluation in ("serial", "processes", "dask"):
        backend = "dask" if evaluation == "dask" else "serial"
        cfg = validate(dict(data, output=str(tmp_path / evaluation),
                            execution={"backend": backend, "evaluation_backend": evaluation, "workers": 2,
                                       "progress": False}))
        run_study(cfg, figures=False)
        outs[evaluation] = _tables(tmp_path / evaluation)
    for evaluation in ("processes", "dask"):
        for name in outs["serial"]:
            pd.testing.assert_frame_equal(outs["serial"][name], outs[evaluation][name], check_exact=True)


# ---- fuzzing the loaders -----------------------------------------------------------------
json_values = st.recursive(
    st.none() | st.booleans() | st.floats(allow_nan=True) | st.integers() | st.text(max_size=5),
    lambda children: st.lists(children, max_size=4) | st.dictionaries(st.text(max_size=8), children, max_size=4),
    max_leaves=12,
)
mode = st.fixed_dictionaries({"frequency_hz": json_values}, optional={"shape": json_values, "label": json_values,
                                                                      "damping_ratio": json_values})


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.fixed_dictionaries({"dofs": json_values, "modes": st.lists(mode, max_size=3) | json_values},
                             optional={"units": json_values, "name": json_values}))
def test_measured_loader_raises_only_input_errors(data):
    try:
        m = measurements.from_dict(data, source="fuzz.yaml")
    except InputError as exc:
        assert "fuzz.yaml" in str(exc)
        return
    assert np.all(np.isfinite(m.frequencies_hz)) and np.all(m.frequencies_hz > 0)
    if m.shapes is not None:
        assert m.shapes.shape == (len(m.dofs), m.n_modes)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.dictionaries(st.sampled_from(["study", "structure", "measured", "algorithms", "runs", "budget",
                                        "parameters", "objective", "sweep", "seed", "execution", "typo"]),
                       json_values, max_size=8))
def test_config_validation_raises_only_input_errors(data):
    try:
        validate(data, source="fuzz.yaml")
    except InputError as exc:
        assert str(exc).startswith("fuzz.yaml")
