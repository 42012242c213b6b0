"""Run kind ``diagnose`` on the engine: gomu diagnose, the hidden-effect study, resume, backends."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pandas as pd
import pytest
import yaml

from framework.cli import main
from framework.core.errors import InputError, ModelEvaluationError
from framework.diagnosis.outcomes import score
from framework.study.config import load, validate
from framework.study.plan import plan
from framework.study.runner import preflight, report, run_study
from framework.study.store import ResultStore
from tests.tables import assert_same_tables

ROOT = Path(__file__).resolve().parents[1]

#: two beam cases of studies/discrepancy.yaml (seed 1, noise high): a null case and a hidden mass
SMALL = {
    "study": "disc_small",
    "kind": "diagnose",
    "structure": "beam",
    "measured": {"generate": {"hidden": {}, "noise": "high"}},
    "seed": 1,
    "settings": {"n_starts": 2, "max_evaluations": 200, "holdout_modes": True},
    "variants": {"beam__none": {"measured.generate.hidden": {}},
                 "beam__midspan_mass": {"measured.generate.hidden": {"midspan_mass": None}}},
    "report": {"outcomes": True, "showcase_seeds": [1]},
    "execution": {"progress": False},
}
TABLES = ("summary", "rounds", "candidates", "modes", "parameters", "comac", "cases", "rates")


def _tables(root: Path) -> dict[str, pd.DataFrame]:
    return {n: pd.read_csv(root / f"{n}.csv") for n in TABLES}


@pytest.fixture(scope="module")
def small_study(tmp_path_factory):
    out = tmp_path_factory.mktemp("disc") / "serial"
    run_study(validate(dict(SMALL, output=str(out))))
    return out


def test_hidden_effect_study_tables_outcomes_and_figures(small_study):
    t = _tables(small_study)
    cases = t["cases"].set_index("id")
    assert list(cases.index) == ["beam__midspan_mass__high__seed1", "beam__none__high__seed1"]
    assert cases.loc["beam__midspan_mass__high__seed1", "named_effect"] == "midspan_mass"
    assert cases.loc["beam__none__high__seed1", "named_effect"] == "none"
    assert cases["correct"].tolist() == [True, False] and not cases["false_discovery"].any()
    rates = t["rates"].set_index("hidden_effect")
    assert rates.loc["midspan_mass", "correct_rate"] == 1.0 and rates.loc["none", "false_discovery_rate"] == 0.0
    # the gap shrinks where the effect was named, and stays where nothing was
    mass = cases.loc["beam__midspan_mass__high__seed1"]
    assert mass["max_freq_error_pct_after"] < mass["max_freq_error_pct_before"] / 3 and mass["p_after"] > 0.01
    # settings are typed columns: data settings in every table, workflow settings in the summary
    for name in ("summary", "rounds", "candidates", "modes", "parameters", "comac"):
        assert {"structure", "hidden_effect", "magnitude", "noise"} <= set(t[name].columns), name
        assert t[name]["magnitude"].dtype == float and set(t[name]["noise"]) == {"high"}
    summary = t["summary"]
    assert summary["n_starts"].tolist() == [2, 2] and summary["holdout_modes"].all()
    assert (summary["status"] == "ok").all() and (summary["n_evaluations"] > 100).all()
    assert summary["data_seed"].tolist() == [1, 1]
    # parameters of every candidate, with the truth of generated data
    params = t["parameters"]
    mass_params = params[(params["hidden_effect"] == "midspan_mass") & (params["round"] == 1)]
    assert set(mass_params["candidate"]) == {"none", "support_rotational_restraint", "localized_stiffness_loss",
                                             "midspan_mass"}
    truth = json.loads(mass["truth"])["midspan_mass_ratio"]
    fitted = mass_params.query("candidate == 'midspan_mass' and parameter == 'midspan_mass_ratio'").iloc[0]
    assert fitted["truth"] == pytest.approx(truth) and fitted["value"] == pytest.approx(truth, rel=0.25)
    assert (small_study / "study.png").stat().st_size > 5_000
    assert sorted(p.name for p in (small_study / "showcase").iterdir()) == [
        "beam__midspan_mass__high__seed1.png", "beam__none__high__seed1.png"]


def test_resume_processes_and_report_reproduce_the_serial_tables(small_study, tmp_path):
    ref = _tables(small_study)
    # resume after losing one run's part
    resumed = tmp_path / "resumed"
    cfg = validate(dict(SMALL, output=str(resumed)))
    run_study(cfg)
    parts = sorted((resumed / "_runs").glob("*.json"))
    parts[0].unlink()
    kept = parts[1].read_text()
    run_study(cfg, resume=True)
    assert parts[1].read_text() == kept  # the stored run was not redone
    assert_same_tables(ref, _tables(resumed))
    # on worker processes
    procs = tmp_path / "processes"
    run_study(validate(dict(SMALL, output=str(procs))), backend="processes", workers=2)
    assert_same_tables(ref, _tables(procs))
    # gomu report redoes the analyses and figures from the stored tables
    (procs / "cases.csv").unlink()
    (procs / "study.png").unlink()
    report(procs)
    assert_same_tables({"cases": ref["cases"]}, {"cases": pd.read_csv(procs / "cases.csv")})
    assert (procs / "study.png").exists()


@pytest.mark.slow
def test_dask_reproduces_the_serial_tables(small_study, tmp_path):
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    try:
        cfg = validate(dict(SMALL, output=str(tmp_path / "d"),
                            execution={"backend": "dask", "scheduler": cluster.scheduler_address, "progress": False}))
        run_study(cfg)
    finally:
        cluster.close()
    assert_same_tables(_tables(small_study), _tables(tmp_path / "d"))


def test_plan_magnitude_once_without_effect_parameters_and_report_keeps_run_ids():
    data = dict(SMALL, sweep={"measured.generate.magnitude": [1.0, 0.3]}, runs=2)
    specs = plan(validate(data))
    # the null case does not depend on the magnitude: planned once per seed
    assert sorted((s["variant"], s["seed"]) for s in specs) == [
        ("beam__midspan_mass,magnitude=0.3", 1), ("beam__midspan_mass,magnitude=0.3", 2),
        ("beam__midspan_mass,magnitude=1.0", 1), ("beam__midspan_mass,magnitude=1.0", 2),
        ("beam__none", 1), ("beam__none", 2)]  # fmt: skip
    none = [s for s in specs if s["variant"] == "beam__none"][0]
    assert none["columns"] == {"structure": "beam", "hidden_effect": "none", "magnitude": 1.0, "noise": "high",
                               "data_stds": True, "candidates": "catalogue"}
    assert none["task"]["settings"]["holdout_modes"] is True and none["task"]["settings"]["alpha"] == 0.01
    # report and execution options never change a run
    other = plan(validate(dict(data, report={"showcase_seeds": [2]}, execution={"backend": "processes"})))
    assert [s["run_id"] for s in other] == [s["run_id"] for s in specs]


def test_catalogue_settings_apply_unless_the_config_sets_them():
    data = {"study": "b", "kind": "diagnose", "structure": "bridge",
            "measured": {"generate": {"hidden": {"bearing_flexibility": None}}}}
    assert plan(validate(data))[0]["task"]["settings"]["frequency_window"] == 0.15
    data["settings"] = {"frequency_window": 0.3}
    assert plan(validate(data))[0]["task"]["settings"]["frequency_window"] == 0.3


def test_study_config_holds_the_cases_of_the_committed_study():
    specs = plan(load(ROOT / "studies" / "discrepancy.yaml"))
    assert len(specs) == 240
    by_structure = pd.Series([s["columns"]["structure"] for s in specs]).value_counts().to_dict()
    assert by_structure == {"beam": 108, "lab_frame": 42, "bridge": 12, "frame_two_bay": 78}
    kinds = pd.Series([(s["columns"]["hidden_effect"], s["columns"]["data_stds"]) for s in specs
                       if s["columns"]["structure"] != "bridge"]).value_counts()  # fmt: skip
    assert kinds[("none", False)] == kinds[("none", True)] == 24  # null cases with and without stds
    bridge = next(s for s in specs if s["columns"]["structure"] == "bridge")["task"]["settings"]
    assert {k: bridge[k] for k in ("n_starts", "max_evaluations", "max_rounds", "frequency_window")} == {
        "n_starts": 1, "max_evaluations": 60, "max_rounds": 2, "frequency_window": 0.15}


def test_gomu_diagnose_runs_a_legacy_config_as_a_one_run_study(tmp_path, capsys):
    cfg = tmp_path / "c.yaml"
    cfg.write_text("name: t\nstructure: beam\nmeasured:\n  generate: {hidden: {midspan_mass: null}, seed: 2, noise: high}\n"
                   "settings: {n_starts: 1, max_evaluations: 150}\n")
    assert main(["diagnose", str(cfg), "--output", str(tmp_path / "out")]) == 0
    printed = capsys.readouterr().out
    assert "named effect(s): midspan_mass" in printed and "gap after:" in printed
    out = tmp_path / "out"
    summary = pd.read_csv(out / "summary.csv")
    assert summary.loc[0, "named_effect"] == "midspan_mass" and summary.loc[0, "study"] == "t"
    assert (out / "discrepancy.png").stat().st_size > 5_000
    modes = pd.read_parquet(out / "modes.parquet")
    assert len(modes) == 10 and set(modes.columns) >= {"f_measured_hz", "f_model_hz", "error_pct", "mac", "matched"}
    # the same diagnosis as a study config of kind diagnose, through gomu run
    new = {"study": "t2", "kind": "diagnose", "structure": "beam", "seed": 2, "output": str(tmp_path / "run"),
           "measured": {"generate": {"hidden": {"midspan_mass": None}, "noise": "high"}},
           "settings": {"n_starts": 1, "max_evaluations": 150}}
    (tmp_path / "new.yaml").write_text(yaml.safe_dump(new))
    assert main(["run", str(tmp_path / "new.yaml"), "--quiet"]) == 0
    again = pd.read_csv(tmp_path / "run" / "summary.csv")
    assert again.loc[0, "chi2_before"] == summary.loc[0, "chi2_before"]
    assert again.loc[0, "chi2_after"] == summary.loc[0, "chi2_after"]


def test_a_failed_diagnosis_is_a_row_and_the_study_goes_on(tmp_path, monkeypatch):
    import framework.study.kinds.diagnose as kind

    real = kind.diagnose

    def flaky(catalogue, measured, settings, start=None):
        if measured.meta["hidden"]:
            raise ModelEvaluationError("eigen_failed", "every evaluation failed")
        return real(catalogue, measured, settings, start=start)

    monkeypatch.setattr(kind, "diagnose", flaky)
    tables = run_study(validate(dict(SMALL, output=str(tmp_path), settings={"n_starts": 1, "max_evaluations": 100})))
    summary = tables["summary"].set_index("hidden_effect")
    assert summary.loc["midspan_mass", "status"] == "failed"
    assert "eigen_failed" in summary.loc["midspan_mass", "error"]
    assert summary.loc["none", "status"] == "ok"
    rates = pd.read_csv(tmp_path / "rates.csv").set_index("hidden_effect")
    assert list(rates.index) == ["none"]  # a failed case is not scored
    assert int(pd.read_csv(tmp_path / "cases.csv").query("hidden_effect == 'midspan_mass'")["correct"].sum()) == 0


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"measured": {"builtin": "lab_frame", "file": "x.yaml"}}, "measured: give exactly one of file, builtin, generate"),
        ({"settings": {"alpha": 2}}, r"settings.alpha: Input should be less than 1 \(value: 2\)"),
        ({"settings": {"n_starts": 1.5}}, r"settings.n_starts: Input should be a valid integer"),
        ({"measured": {"file": "missing.yaml"}}, "measured.file: file not found: missing.yaml"),
        ({"measured": {"builtin": "lab_frame"}, "runs": 3}, "runs: 3 runs would repeat one diagnosis"),
        ({"measured": {"generate": {"noise": "loud"}}},
         r"measured.generate.noise.level: Input should be 'low', 'high' or 'very_high' \(value: 'loud'\)"),
        ({"measured": {"generate": {"noise": {"frequency_std_rel": 0, "shape_std_rel": 0.01}}}},
         r"measured.generate.noise.std.frequency_std_rel: Input should be greater than 0"),
        ({"report": {"showcase": [1]}}, r"report.showcase: unknown key; known: \['outcomes', 'showcase_seeds'\] \(value: \[1\]\)"),
        ({"structure": "nope"}, "structure 'nope' has no effect catalogue"),
        ({"measured": {"generate": {"hidden": {"bogus": None}}}}, "effect 'bogus' unknown"),
        ({"start_effects": {"midspan_mass": "e03"}}, "effect 'midspan_mass' variant 'e03' unknown"),
        ({"measured": {"generate": {"hidden": {"midspan_mass": None}, "values": {"EI_ratio": 1.0}}}},
         r"measured.generate.values: \['EI_ratio'\] are not parameters of the hidden effects"),
    ],
)
def test_bad_config_is_one_line_naming_field_and_value(tmp_path, capsys, change, message):
    data = {"study": "t", "kind": "diagnose", "structure": "beam", "measured": {"generate": {}}} | change
    path = tmp_path / "c.yaml"
    path.write_text(yaml.safe_dump(data))
    for command in ("validate", "diagnose"):
        assert main([command, str(path)]) == 2
        err = capsys.readouterr().err
        assert err.startswith("gomu: error: ") and len(err.strip().splitlines()) == 1, err
        assert re.search(message, err), err
    with pytest.raises(InputError):
        cfg = load(path)
        preflight(cfg, plan(cfg))


def test_gomu_diagnose_refuses_a_study_of_many_runs(tmp_path, capsys):
    path = tmp_path / "c.yaml"
    path.write_text(yaml.safe_dump(dict(SMALL, output=str(tmp_path / "o"))))
    assert main(["diagnose", str(path)]) == 2
    assert "gomu diagnose runs one diagnosis, this config plans 2; use gomu run" in capsys.readouterr().err


def test_bad_data_file_fails_before_any_run(tmp_path):
    (tmp_path / "modes.yaml").write_text("dofs: [nope]\nmodes:\n- {frequency_hz: 1.0, shape: [1.0]}\n")
    data = {"study": "t", "kind": "diagnose", "structure": "beam", "measured": {"file": "modes.yaml"},
            "output": str(tmp_path / "o")}
    (tmp_path / "c.yaml").write_text(yaml.safe_dump(data))
    with pytest.raises(InputError, match=r"measured DOF\(s\) \['nope'\] are not DOFs"):
        run_study(load(tmp_path / "c.yaml"))
    assert not ResultStore(tmp_path / "o").stored_ids()


def test_outcome_rules():
    both = "semi_rigid_joints+sensor_mass_eccentricity"
    assert score(both, "sensor_mass_eccentricity+semi_rigid_joints")["correct"]  # order does not matter
    assert score(both, "semi_rigid_joints") == {"correct": False, "variant_correct": False, "wrong": False,
                                                "subset_named": True, "missed": False, "false_discovery": False}
    assert score("midspan_mass", "support_rotational_restraint")["wrong"]
    assert score("midspan_mass", "none")["missed"] and score("none", "midspan_mass")["false_discovery"]
    assert not any(score("none", "none").values())
    flags = score("localized_stiffness_loss", "localized_stiffness_loss", "e03", "e04")
    assert flags["correct"] and not flags["variant_correct"]
