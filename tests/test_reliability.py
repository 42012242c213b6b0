"""Issue 14, defect by defect, through the command line (``framework.cli.main``) as a user
meets it: each test names the numbered defect it reproduces. Input errors must end with
exit code 2 and one line ``gomu: error: <file>: <field>: ...`` on stderr, no traceback."""

import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from framework.cli import main

ROOT = Path(__file__).resolve().parents[1]

BASE = {
    "study": "rel",
    "structure": {"name": "lab_frame_3dof"},
    "measured": {"builtin": "lab_frame", "case": "base"},
    "budget": {"max_evaluations": 60, "stall_iterations": 20},
    "algorithms": {"sm": {"algorithm": "sm"}},
    "runs": 1,
    "execution": {"progress": False},
}
GOOD_DATA = "dofs: [y, x, torsion]\nmodes:\n  - {frequency_hz: 3.58, shape: [1.0, 0.004, -0.01]}\n"


def _write(tmp_path, config: dict | str, name: str = "study.yaml") -> Path:
    path = tmp_path / name
    if isinstance(config, dict):
        config = yaml.safe_dump({"output": str(tmp_path / "out"), **config}, sort_keys=False)
    path.write_text(config)
    return path


def _gomu(capsys, *argv) -> tuple[int, str, str]:
    """Run the CLI in this process; (exit code, stdout, stderr)."""
    try:
        code = main([str(a) for a in argv])
    except SystemExit as exc:  # argparse
        code = exc.code
    out, err = capsys.readouterr()
    return code, out, err


def _one_line_error(code: int, err: str, *patterns: str) -> None:
    assert code == 2, err
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(("gomu: error: ", "gomu run: error: ")), err
    for pattern in patterns:
        assert re.search(pattern, lines[0]), lines[0]


# ---- 1. nsga2 in a study --------------------------------------------------------------------
def test_1_nsga2_run_in_a_gomu_run_study_ends_with_its_rows_stored(tmp_path, capsys):
    cfg = _write(tmp_path, dict(BASE, algorithms={
        "nsga2": {"algorithm": "nsga2", "settings": {"pop_size": 10, "n_generations": 4}},
        "nsga2_small_budget": {"algorithm": "nsga2", "budget": {"max_evaluations": 5}}}))
    code, _, err = _gomu(capsys, "run", cfg, "--no-figures")
    assert code == 0, err
    runs = pd.read_csv(tmp_path / "out" / "runs.csv").set_index("label")
    assert runs.loc["nsga2", "status"] == "max_generations" and runs.loc["nsga2", "n_evaluations"] == 40
    # a budget below one population (default 500) is a failed run with nothing evaluated, not an error
    assert runs.loc["nsga2_small_budget", "status"] == "failed"
    assert runs.loc["nsga2_small_budget", "n_evaluations"] == 0
    extra = pd.read_csv(tmp_path / "out" / "extra.csv")
    pareto = json.loads(extra.loc[extra.key == "pareto_F", "value"].iloc[0])
    assert len(pareto) >= 1 and len(pareto[0]) == 2
    params = pd.read_csv(tmp_path / "out" / "parameters.csv")
    assert set(params["label"]) == {"nsga2"}  # no updated values from the failed run


# ---- 2. damaged parts -----------------------------------------------------------------------
def test_2_every_kind_of_damaged_part_is_quarantined_and_recomputed_on_resume(tmp_path, capsys):
    cfg = _write(tmp_path, dict(BASE, algorithms={"sm": {"algorithm": "sm", "settings": {"start": "random"}}},
                                runs=6))
    assert _gomu(capsys, "run", cfg, "--no-figures")[0] == 0
    out = tmp_path / "out"
    ref = pd.read_csv(out / "runs.csv").drop(columns="wall_s")
    parts = sorted((out / "_runs").glob("*.json"))
    parts[0].write_bytes(b"")  # empty
    parts[1].write_bytes(parts[1].read_bytes()[:60])  # cut in half
    parts[2].write_bytes(b"\xff\xfe garbage")  # not UTF-8, not JSON
    parts[3].write_text("[1, 2, 3]")  # a JSON list
    parts[4].write_bytes(parts[5].read_bytes())  # another run's rows
    code, _, err = _gomu(capsys, "run", cfg, "--no-figures", "--resume")
    assert code == 0, err
    assert len(list((out / "_runs" / "_damaged").glob("*.json"))) == 5
    again = pd.read_csv(out / "runs.csv").drop(columns="wall_s")
    assert again["run_id"].is_unique
    pd.testing.assert_frame_equal(again, ref)


# ---- 3, 4. inputs misread or crashing at the end ----------------------------------------------
MISREAD = [
    # (id, config changes, data file name, data text, expected pattern)
    ("decimal_comma_csv", {}, "m.csv", "label,frequency_hz\n1st y,3,58\n", r"m\.csv: line 2: .*decimal comma"),
    ("decimal_comma_csv_3_columns", {}, "m.csv", "label,frequency_hz,damping_ratio\n1st y,3,58\n",
     r"m\.csv: .*damping"),
    ("duplicate_key_config", "runs: 1\nruns: 2\n", None, None, r"study\.yaml: runs: duplicate key \(line \d+"),
    ("duplicate_key_data", {}, "m.yaml", "dofs: [y]\ndofs: [x]\nmodes:\n  - {frequency_hz: 3.58}\n",
     r"m\.yaml: dofs: duplicate key"),
    ("mode_zero", {"measured": {"builtin": "lab_frame", "modes": [0]}}, None, None, r"measured.*numbered from 1"),
    ("mode_minus_one", {"measured": {"builtin": "lab_frame", "modes": [-1]}}, None, None,
     r"measured.*numbered from 1"),
    ("dofs_text", {}, "m.yaml", "dofs: \"yx\"\nmodes:\n  - {frequency_hz: 3.58, shape: [1.0, 0.1]}\n",
     r"m\.yaml: dofs: must be a list"),
    ("runs_true", {"runs": True}, None, None, r"study\.yaml: runs: .*integer \(value: True\)"),
    ("huge_bounds", {"parameters": {"bounds": {"kxx": [-1.7e308, 1.7e308]}}}, None, None,
     r"study\.yaml: parameters\.bounds\.kxx: bounds must be finite"),
    ("label_int_next_to_text", {}, "m.yaml",
     "dofs: [y, x, torsion]\nmodes:\n  - {label: 1, frequency_hz: 3.58, shape: [1.0, 0.0, 0.0]}\n"
     "  - {label: 1st x, frequency_hz: 5.01, shape: [0.0, 1.0, 0.0]}\n", r"m\.yaml: modes\[0\]\.label: must be text"),
    ("label_mapping", {}, "m.yaml", "dofs: [y]\nmodes:\n  - {label: {a: 1}, frequency_hz: 3.58, shape: [1.0]}\n",
     r"m\.yaml: modes\[0\]\.label: must be text"),
    ("seed_1e23", {"seed": 1e23}, None, None, r"study\.yaml: seed: .*integer"),
    ("alpha_beta_zero", {"objective": {"alpha": 0, "beta": 0}}, None, None, r"objective: alpha and beta are both 0"),
    ("failure_penalty_zero", {"objective": {"failure_penalty": 0}}, None, None, r"objective\.failure_penalty"),
    ("nan_target", {"budget": {"max_evaluations": 10, "target_objective": float("nan")}}, None, None,
     r"budget\.target_objective: .*finite"),
    ("infinite_setting", {"algorithms": {"pso": {"algorithm": "pso", "settings": {"factor": float("inf")}}}}, None,
     None, r"algorithms\.pso: settings\.factor: .*finite"),
    ("text_number", {"objective": {"alpha": "1"}}, None, None, r"objective\.alpha: .*expected a number"),
    ("timeout_true", {"execution": {"evaluation_timeout_s": True}}, None, None,
     r"execution\.evaluation_timeout_s: expected a number"),
]


@pytest.mark.parametrize("case_id, changes, data_name, data_text, pattern", MISREAD, ids=[m[0] for m in MISREAD])
def test_3_4_5_inputs_are_refused_at_validation_never_misread(tmp_path, capsys, case_id, changes, data_name,
                                                              data_text, pattern):
    if isinstance(changes, str):  # raw YAML text appended to the base config
        cfg = _write(tmp_path, yaml.safe_dump(dict(BASE, runs=None)).replace("runs: null\n", "") + changes)
    else:
        data = json.loads(json.dumps({**BASE, **changes}))
        if data_name:
            (tmp_path / data_name).write_text(data_text)
            data["measured"] = {"file": data_name}
        cfg = _write(tmp_path, data)
    code, _, err = _gomu(capsys, "validate", cfg)
    _one_line_error(code, err, pattern)
    code, _, err = _gomu(capsys, "run", cfg, "--no-figures")
    _one_line_error(code, err, pattern)
    assert not (tmp_path / "out").exists()  # nothing started, nothing written


def test_4_text_labels_that_look_like_numbers_reach_the_tables(tmp_path, capsys):
    (tmp_path / "m.csv").write_text("label,frequency_hz\n1,3.58\n1st x,5.01\n")
    cfg = _write(tmp_path, dict(BASE, measured={"file": "m.csv"}))
    code, _, err = _gomu(capsys, "run", cfg, "--no-figures")
    assert code == 0, err
    modes = pd.read_csv(tmp_path / "out" / "modes.csv", dtype={"mode_label": str})
    assert modes["mode_label"].tolist() == ["1", "1st x"]
    assert code == 0 and _gomu(capsys, "run", cfg, "--no-figures", "--resume")[0] == 0


# ---- 5. failed points are not results -------------------------------------------------------
def test_5_an_sm_run_whose_evaluations_all_failed_is_failed_with_no_updated_values(tmp_path, capsys, monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT / "tests"))
    cfg = _write(tmp_path, dict(BASE, structure={"name": "fault_models:make_holey", "options": {"kxx_limit": 0.0}},
                                objective={"failure_penalty": 1e-9}, budget={"max_evaluations": 40}))
    code, _, err = _gomu(capsys, "run", cfg, "--no-figures")
    assert code == 0, err
    runs = pd.read_csv(tmp_path / "out" / "runs.csv")
    assert runs["status"].tolist() == ["failed"] and np.isnan(runs["objective"]).all()
    assert "every evaluation failed" in runs["message"].iloc[0]
    assert (tmp_path / "out" / "parameters.csv").read_text().strip() == ""  # no rows, not the failed point
    failures = pd.read_csv(tmp_path / "out" / "failures.csv")
    assert failures["reason"].tolist() == ["not_converged"]
    assert failures["n_failed"].iloc[0] == runs["n_evaluations"].iloc[0]


# ---- 6. a user's build function cannot stop or hang the study (no isolation configured) ----------
def test_6_a_crashing_exiting_or_hanging_user_build_is_contained_by_default(tmp_path, capsys, monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))
    cfg = _write(tmp_path, dict(BASE, structure={"name": "tests.faulty_build:make_model", "options": {"hang_s": 60}},
                                measured={"builtin": "tests.faulty_build:measured"},
                                budget={"max_evaluations": 200, "target_objective": None},
                                algorithms={"ga": {"algorithm": "ga", "settings": {"pop_size": 100}}},
                                execution={"progress": False, "evaluation_timeout_s": 1.0}))
    code, _, err = _gomu(capsys, "run", cfg, "--no-figures")  # a segfault here would end pytest itself
    assert code == 0, err
    runs = pd.read_csv(tmp_path / "out" / "runs.csv")
    # toolbox GA: 100, then 98 per generation (2 elite children are not evaluated again)
    assert runs["status"].tolist() == ["budget"] and runs["n_evaluations"].iloc[0] == 198
    reasons = set(pd.read_csv(tmp_path / "out" / "failures.csv")["reason"])
    assert {"worker_crashed", "model_exit", "timeout", "build_failed"} <= reasons


def test_6_isolation_is_automatic_for_user_code_only():
    from framework.study.schema import DEFAULT_EVALUATION_TIMEOUT_S, evaluation_isolation

    assert evaluation_isolation({}, names_code=False) == (False, None)
    assert evaluation_isolation({}, names_code=True) == (True, DEFAULT_EVALUATION_TIMEOUT_S)
    assert evaluation_isolation({"isolate": False}, names_code=True) == (False, None)
    assert evaluation_isolation({"isolate": True}, names_code=False) == (True, DEFAULT_EVALUATION_TIMEOUT_S)
    assert evaluation_isolation({"evaluation_timeout_s": 2.0}, names_code=False) == (True, 2.0)


# ---- 7. one line, not a traceback --------------------------------------------------------------
def test_7_bad_files_and_paths(tmp_path, capsys):
    (tmp_path / "latin1.yaml").write_bytes(b"study: caf\xe9\n")
    _one_line_error(*_gomu(capsys, "validate", tmp_path / "latin1.yaml")[::2], r"latin1\.yaml: .*not UTF-8")
    (tmp_path / "folder.yaml").mkdir()
    _one_line_error(*_gomu(capsys, "validate", tmp_path / "folder.yaml")[::2], r"folder\.yaml: is a folder")
    _write(tmp_path, "a: " + "[" * 3000 + "]" * 3000 + "\n", "deep.yaml")
    _one_line_error(*_gomu(capsys, "validate", tmp_path / "deep.yaml")[::2], r"deep\.yaml: .*nesting")
    (tmp_path / "m.yaml").write_bytes(GOOD_DATA.encode() + b"# caf\xe9\n")
    cfg = _write(tmp_path, dict(BASE, measured={"file": "m.yaml"}))
    _one_line_error(*_gomu(capsys, "validate", cfg)[::2], r"m\.yaml: .*not UTF-8")
    (tmp_path / "dir.yaml").mkdir()
    cfg = _write(tmp_path, dict(BASE, measured={"file": "dir.yaml"}))
    _one_line_error(*_gomu(capsys, "validate", cfg)[::2], r"study\.yaml: measured\.file: is a folder")
    (tmp_path / "huge.yaml").write_text("dofs: [y]\nmodes:\n  - {frequency_hz: 1" + "0" * 5000 + "}\n")
    cfg = _write(tmp_path, dict(BASE, measured={"file": "huge.yaml"}))
    _one_line_error(*_gomu(capsys, "validate", cfg)[::2], r"huge\.yaml: .*too large")
    (tmp_path / "huge.csv").write_text("frequency_hz\n1" + "0" * 400 + "\n")
    cfg = _write(tmp_path, dict(BASE, measured={"file": "huge.csv"}))
    _one_line_error(*_gomu(capsys, "validate", cfg)[::2], r"huge\.csv: line 2, column 'frequency_hz': .*range")


def test_7_bad_command_lines(tmp_path, capsys, monkeypatch):
    cfg = _write(tmp_path, BASE)
    _one_line_error(*_gomu(capsys, "validate", cfg, "--set", "measured.modes=[99]")[::2],
                    r"study\.yaml: .*measured\.modes: mode 99 does not exist")
    _one_line_error(*_gomu(capsys, "run", cfg, "--workers", "-1")[::2], r"--workers: expected a whole number")
    (tmp_path / "file").write_text("x")
    _one_line_error(*_gomu(capsys, "run", cfg, "--set", f"output={tmp_path / 'file'}")[::2],
                    r"exists and is not a folder")
    import framework.execution.parallel

    monkeypatch.setattr(framework.execution.parallel, "CONNECT_TIMEOUT_S", 0.5)
    _one_line_error(*_gomu(capsys, "run", cfg, "--scheduler", "tcp://127.0.0.1:1")[::2],
                    r"study\.yaml: execution\.scheduler \(or --scheduler\) tcp://127\.0\.0\.1:1: cannot connect")
    _one_line_error(*_gomu(capsys, "validate", cfg, "--set", "execution.scheduler=nowhere")[::2],
                    r"execution\.scheduler: a Dask scheduler address")
    assert not (tmp_path / "out").exists()


def test_7_an_unreachable_scheduler_touches_no_stored_run(tmp_path, capsys, monkeypatch):
    import framework.execution.parallel

    cfg = _write(tmp_path, BASE)
    assert _gomu(capsys, "run", cfg, "--no-figures")[0] == 0
    before = sorted(p.name for p in (tmp_path / "out" / "_runs").glob("*.json"))
    monkeypatch.setattr(framework.execution.parallel, "CONNECT_TIMEOUT_S", 0.5)
    code, _, err = _gomu(capsys, "run", cfg, "--scheduler", "127.0.0.1:1")  # without --resume
    _one_line_error(code, err, "cannot connect")
    assert sorted(p.name for p in (tmp_path / "out" / "_runs").glob("*.json")) == before


def _read_only(path: Path):
    """Make a folder unwritable even for root (chattr +i), or skip; returns the undo."""
    if shutil.which("chattr") is None:
        pytest.skip("chattr not available")
    done = subprocess.run(["chattr", "+i", str(path)], capture_output=True)
    if done.returncode != 0:
        pytest.skip(f"cannot make {path} read-only: {done.stderr.decode().strip()}")
    return lambda: subprocess.run(["chattr", "-i", str(path)], check=True)


@pytest.mark.parametrize("folder", ["out", "out/_runs"])
def test_7_a_read_only_output_folder_is_refused_before_any_run(tmp_path, capsys, folder):
    cfg = _write(tmp_path, dict(BASE, runs=2))
    assert _gomu(capsys, "run", cfg, "--no-figures", "--set", "runs=1")[0] == 0
    stored = sorted((tmp_path / "out" / "_runs").glob("*.json"))
    undo = _read_only(tmp_path / folder)
    try:
        code, _, err = _gomu(capsys, "run", cfg, "--no-figures", "--resume")
    finally:
        undo()
    _one_line_error(code, err, r"not writable")
    assert sorted((tmp_path / "out" / "_runs").glob("*.json")) == stored


def test_7_report_on_an_empty_folder_or_a_damaged_table(tmp_path, capsys):
    (tmp_path / "empty").mkdir()
    _one_line_error(*_gomu(capsys, "report", tmp_path / "empty")[::2], r"no config\.yaml")
    _one_line_error(*_gomu(capsys, "report", tmp_path / "none")[::2], r"results folder not found")
    cfg = _write(tmp_path, BASE)
    assert _gomu(capsys, "run", cfg, "--no-figures")[0] == 0
    (tmp_path / "out" / "runs.parquet").write_bytes(b"PAR1 cut")
    _one_line_error(*_gomu(capsys, "report", tmp_path / "out")[::2], r"runs\.parquet: damaged table")
    (tmp_path / "out" / "config.yaml").write_bytes(b"\xff\xfe")
    _one_line_error(*_gomu(capsys, "report", tmp_path / "out")[::2], r"config\.yaml: .*not UTF-8")


def test_7_python_api_arguments_of_the_wrong_type():
    from framework.core.errors import InputError
    from framework.structures.lab_frame.model import ThreeDofFrame, measured
    from framework.updating.problem import UpdatingProblem

    with pytest.raises(InputError, match="argument 'measured' must be MeasuredModes"):
        UpdatingProblem(ThreeDofFrame(), {"frequency_hz": [3.58]})
    with pytest.raises(InputError, match="argument 'model' must be a structural model"):
        UpdatingProblem({"kxx": 1.0}, measured())


# ---- 8. resource exhaustion ------------------------------------------------------------------
def test_8_alias_bomb_and_huge_run_counts_are_refused(tmp_path, capsys):
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x]"]
    lines += [f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 9) + "]" for i in range(1, 12)]
    _write(tmp_path, "\n".join(lines) + "\nstudy: x\n", "bomb.yaml")
    _one_line_error(*_gomu(capsys, "validate", tmp_path / "bomb.yaml")[::2], r"bomb\.yaml: aliases expand")
    cfg = _write(tmp_path, yaml.safe_dump(dict(BASE, runs=None)).replace("runs: null", "runs: 1e9"))
    _one_line_error(*_gomu(capsys, "validate", cfg)[::2], r"study\.yaml: runs: .*integer")
    _one_line_error(*_gomu(capsys, "validate", cfg, "--set", "runs=1000000000")[::2], r"runs: .*less than")


# ---- 9. no code run from data ----------------------------------------------------------------
@pytest.mark.parametrize("changes", [
    {"measured": {"builtin": "os:system", "case": "touch {marker}"}},
    {"validation": [{"case": "v", "measured": {"builtin": "os:system", "case": "touch {marker}"}}]},
    {"structure": {"name": "os:system", "options": {"command": "touch {marker}"}}},
    {"kind": "analysis", "structure": {"name": "os:system", "options": {"command": "touch {marker}"}},
     "algorithms": None, "budget": None},
    {"kind": "diagnose", "structure": "os:system", "structure_options": {"command": "touch {marker}"},
     "measured": {"builtin": "lab_frame"}, "algorithms": None, "budget": None},
    {"kind": "diagnose", "structure": "lab_frame", "measured": {"builtin": "os:system", "case": "touch {marker}"},
     "algorithms": None, "budget": None},
], ids=["measured", "validation", "structure", "analysis_structure", "diagnose_structure", "diagnose_measured"])
def test_9_a_config_cannot_run_library_code(tmp_path, capsys, changes):
    marker = tmp_path / "pwned"
    data = json.loads(json.dumps({**BASE, **changes}).replace("{marker}", str(marker)))
    data = {k: v for k, v in data.items() if v is not None}
    cfg = _write(tmp_path, data)
    for argv in (["validate", cfg], ["validate", cfg, "--build"], ["run", cfg, "--no-figures"]):
        code, _, err = _gomu(capsys, *argv)
        _one_line_error(code, err, r"os:system")
    assert not marker.exists()


def test_9_validate_imports_no_user_data_provider_of_a_diagnosis(tmp_path, capsys, monkeypatch):
    marker = tmp_path / "imported"
    (tmp_path / "rel_user_data.py").write_text(
        f"import pathlib\npathlib.Path({str(marker)!r}).write_text('x')\n"
        "def data(case):\n    from framework.structures.lab_frame.model import measured\n    return measured(case)\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    cfg = _write(tmp_path, {"study": "d", "kind": "diagnose", "structure": "lab_frame",
                            "measured": {"builtin": "rel_user_data:data"}})
    code, out, err = _gomu(capsys, "validate", cfg)
    assert code == 0 and "was not imported" in out, err
    assert not marker.exists()


# ---- 10. folders and budgets -----------------------------------------------------------------
def test_10_study_b_never_deletes_study_a_runs(tmp_path, capsys):
    a = _write(tmp_path, dict(BASE, runs=2), "a.yaml")
    assert _gomu(capsys, "run", a, "--no-figures")[0] == 0
    parts = tmp_path / "out" / "_runs"
    stored = {p.name: p.read_bytes() for p in parts.glob("*.json")}
    b = _write(tmp_path, dict(BASE, study="other", runs=2), "b.yaml")
    for extra in ([], ["--resume"]):
        _one_line_error(*_gomu(capsys, "run", b, "--no-figures", *extra)[::2], r"holds the results of study 'rel'")
    (tmp_path / "out" / "study.json").unlink()  # a folder of an older version: the parts name their study
    (tmp_path / "out" / "config.yaml").unlink()
    _one_line_error(*_gomu(capsys, "run", b, "--no-figures")[::2], r"holds the results of study 'rel'")
    assert {p.name: p.read_bytes() for p in parts.glob("*.json")} == stored


def test_10_a_study_name_cannot_leave_the_results_folder(tmp_path, capsys):
    cfg = _write(tmp_path, yaml.safe_dump(dict(BASE, study="../../escape")))
    _one_line_error(*_gomu(capsys, "validate", cfg)[::2], r"study: study name must be")


def test_10_snt_spends_the_total_budget_not_one_per_minimum():
    from framework.optimizers import Budget, run_optimizer
    from framework.structures.lab_frame.model import measured
    from framework.structures.registry import make_structure
    from framework.updating.problem import UpdatingProblem

    problem = UpdatingProblem(make_structure("lab_frame_3dof"), measured())
    result = run_optimizer("snt", problem, 0, Budget(max_evaluations=600), n_minima=4)
    assert 0 < result.n_evaluations <= 600


def test_8_a_sweep_grid_is_counted_before_it_is_built(tmp_path, capsys):
    sweep = {f"algorithms.sm.settings.{k}": [1e-3 * (i + 1) for i in range(50)]
             for k in ("xtol", "ftol", "gtol", "initial_step", "min_step", "max_step")}  # 50**6 variants
    cfg = _write(tmp_path, dict(BASE, sweep=sweep))
    _one_line_error(*_gomu(capsys, "validate", cfg)[::2], r"15625000000 variants, more than the limit")
