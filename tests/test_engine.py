"""The experiment engine: run identity, settings as columns, the store's guarantees."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from framework.core.errors import InputError
from framework.core.tables import read_table, write_table
from framework.study.config import validate
from framework.study.plan import plan
from framework.study.runner import run_study
from framework.study.store import ResultStore

SMALL = {
    "study": "engine",
    "structure": {"name": "lab_frame_3dof"},
    "measured": {"builtin": "lab_frame", "case": "base"},
    "budget": {"max_evaluations": 200, "stall_iterations": 20},
    "algorithms": {"pso": {"algorithm": "pso", "settings": {"swarm_size": 10}}, "sm": {"algorithm": "sm", "runs": 1}},
    "runs": 2,
    "execution": {"progress": False},
}


def test_report_and_execution_options_keep_every_run_id():
    ids = {s["run_id"] for s in plan(validate(SMALL))}
    changed = dict(SMALL, report={"selection": {"tolerance": 1e-3}}, description="other words",
                   execution={"backend": "processes", "workers": 3, "progress": True}, output="elsewhere",
                   study="renamed")
    assert {s["run_id"] for s in plan(validate(changed))} == ids
    # a setting that changes results changes the id; spelling out a default does not
    assert {s["run_id"] for s in plan(validate(dict(SMALL, seed=1)))} != ids
    spelled = json.loads(json.dumps(SMALL))
    spelled["algorithms"]["pso"]["settings"]["factor"] = 0.75
    assert {s["run_id"] for s in plan(validate(spelled))} == ids


def test_swept_and_configured_settings_are_typed_columns(tmp_path):
    cfg = validate(dict(SMALL, output=str(tmp_path / "o"), sweep={"algorithms.pso.settings.swarm_size": [4, 8]}))
    tables = run_study(cfg, figures=False)
    runs = tables["runs"]
    pso = runs[runs["label"] == "pso"]
    assert sorted(pso["swarm_size"].unique().tolist()) == [4, 8]
    assert pd.api.types.is_integer_dtype(pso["swarm_size"])
    assert pd.api.types.is_float_dtype(runs["factor"])  # a configured (default) setting of PSO
    sm = runs[runs["label"] == "sm"]
    assert len(sm) == 1 and sm["variant"].iloc[0] == "default"  # not duplicated by the PSO sweep
    assert "swarm_size" in tables["history"].columns  # swept settings are columns of every table
    assert set(runs["kind"]) == {"updating"}


def test_named_variants_apply_overrides():
    cfg = validate(dict(SMALL, variants={"low": {"budget.max_evaluations": 100}, "high": {}}))
    specs = plan(cfg)
    budgets = {s["variant"]: s["task"]["budget"]["max_evaluations"] for s in specs if s["label"] == "sm"}
    assert budgets == {"low": 100, "high": 200}


@pytest.mark.parametrize("damage", [b"", b'{"tables": {"runs": [{"run_id": "x"', b"\xff\xfe garbage",
                                    b"[1, 2, 3]", b'{"tables": {"runs": "not rows"}}'])
def test_a_damaged_part_is_quarantined_and_recomputed(tmp_path, damage):
    out = tmp_path / "o"
    cfg = validate(dict(SMALL, output=str(out)))
    ref = run_study(cfg, figures=False)["runs"]
    victim = sorted((out / "_runs").glob("*.json"))[0]
    victim.write_bytes(damage)
    tables = run_study(cfg, resume=True, figures=False)
    assert len(list((out / "_runs" / "_damaged").glob("*.json"))) == 1
    pd.testing.assert_frame_equal(tables["runs"].drop(columns="wall_s"), ref.drop(columns="wall_s"))


def test_a_part_holding_another_runs_rows_is_not_accepted(tmp_path):
    out = tmp_path / "o"
    cfg = validate(dict(SMALL, output=str(out)))
    run_study(cfg, figures=False)
    a, b = sorted((out / "_runs").glob("*.json"))[:2]
    b.write_text(a.read_text())  # a copy of run a under run b's name
    tables = run_study(cfg, resume=True, figures=False)
    assert tables["runs"]["run_id"].is_unique and len(tables["runs"]) == 3


def test_another_study_in_the_same_folder_is_refused(tmp_path):
    out = tmp_path / "shared"
    run_study(validate(dict(SMALL, output=str(out))), figures=False)
    n = len(list((out / "_runs").glob("*.json")))
    with pytest.raises(InputError, match="holds the results of study 'engine'"):
        run_study(validate(dict(SMALL, study="other", output=str(out))), figures=False)
    assert len(list((out / "_runs").glob("*.json"))) == n


@pytest.mark.parametrize("field, value, message", [
    ("study", "../escape", "study: study name must be"),
    ("runs", True, "runs: Input should be a valid integer"),
    ("seed", 1e23, "seed: Input should be a valid integer"),
    ("runs", 10**9, "runs: Input should be less than or equal to 100000"),
])
def test_strict_header_fields(field, value, message):
    with pytest.raises(InputError, match=message):
        validate(dict(SMALL, **{field: value}), source="cfg.yaml")


def test_output_that_is_a_file_is_an_input_error(tmp_path):
    target = tmp_path / "file"
    target.write_text("x")
    with pytest.raises(InputError, match="exists and is not a folder"):
        run_study(validate(dict(SMALL, output=str(target))), figures=False)


def test_mixed_type_columns_are_stored_as_text(tmp_path):
    df = pd.DataFrame({"mode_label": [1, "1st x", {"a": 1}], "value": [1.0, np.nan, 3.0]})
    write_table(df, tmp_path / "t")
    back = read_table(tmp_path, "t")
    assert back["mode_label"].tolist() == ["1", "1st x", '{"a": 1}']


def test_report_on_a_damaged_table_or_an_empty_folder_is_an_input_error(tmp_path):
    from framework.study.runner import report

    (tmp_path / "empty").mkdir()
    with pytest.raises(InputError, match="no config.yaml"):
        report(tmp_path / "empty")
    out = tmp_path / "o"
    run_study(validate(dict(SMALL, output=str(out))), figures=False)
    (out / "runs.parquet").write_bytes(b"PAR1 not really")
    with pytest.raises(InputError, match="damaged table"):
        report(out)


def test_store_ignores_rows_of_unwanted_runs(tmp_path):
    store = ResultStore(tmp_path)
    store.claim("s")
    store.write_run("a", {"runs": [{"run_id": "a", "label": "x"}]}, study="s", kind="updating")
    store.write_run("b", {"runs": [{"run_id": "b", "label": "y"}]}, study="s", kind="updating")
    assert store.read_parts({"a"})["runs"]["run_id"].tolist() == ["a"]


def test_validate_imports_no_code_named_in_the_config_unless_asked(tmp_path, monkeypatch, capsys):
    from framework.cli import main

    marker = tmp_path / "imported"
    (tmp_path / "user_model.py").write_text(
        "import pathlib\n"
        f"pathlib.Path({str(marker)!r}).write_text('x')\n"
        "from framework.structures.lab_frame.model import make_model as _make\n"
        "def make_model(**options):\n    return _make(**options)\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    import yaml

    cfg = tmp_path / "c.yaml"
    cfg.write_text(yaml.safe_dump(dict(SMALL, structure={"name": "user_model:make_model"})))
    assert main(["validate", str(cfg)]) == 0
    assert not marker.exists()
    assert "was not imported" in capsys.readouterr().out
    assert main(["validate", str(cfg), "--build"]) == 0
    assert marker.exists()


@pytest.mark.parametrize("reference", ["os:system", "subprocess:run", "framework.structures.lab_frame.model:np"])
def test_references_to_non_user_code_are_refused(tmp_path, reference):
    data = dict(SMALL, measured={"builtin": reference, "case": f"touch {tmp_path / 'pwned'}"},
                output=str(tmp_path / "o"))
    with pytest.raises(InputError, match="measured.builtin"):
        run_study(validate(data), figures=False)
    assert not (tmp_path / "pwned").exists()


def test_gomu_finds_a_module_in_the_current_folder(tmp_path, monkeypatch):
    import subprocess
    import sys

    import yaml

    (tmp_path / "mine.py").write_text(
        "from framework.structures.lab_frame.model import make_model as _make\n"
        "def make_model(**options):\n    return _make(**options)\n")
    (tmp_path / "c.yaml").write_text(yaml.safe_dump(dict(SMALL, structure={"name": "mine:make_model"})))
    gomu = Path(sys.executable).parent / "gomu"  # the console script: no '' on sys.path by itself
    if not gomu.exists():
        pytest.skip("the gomu console script is not installed")
    done = subprocess.run([str(gomu), "validate", "c.yaml", "--build"], cwd=tmp_path, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr


def test_results_folder_records_provenance(tmp_path):
    out = tmp_path / "o"
    run_study(validate(dict(SMALL, output=str(out), runs=1)), figures=False)
    prov = json.loads((out / "provenance.json").read_text())
    assert prov["packages"]["numpy"] == __import__("numpy").__version__
    assert {"git", "python", "platform", "command"} <= set(prov)
