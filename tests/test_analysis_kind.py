"""Run kind ``analysis``: a model at given points; reproducible in serial, process, resumed
and Dask execution; sensitivities through the one sensitivity function; input errors."""

import numpy as np
import pandas as pd
import pytest
import yaml

from framework.core.errors import InputError
from framework.structures.lab_frame.model import make_model, measured
from framework.study.config import validate
from framework.study.plan import plan
from framework.study.runner import run_study
from framework.updating.problem import UpdatingProblem
from framework.updating.sensitivity import sensitivity_matrix
from tests.tables import assert_same_tables

SMALL = {
    "study": "small_analysis",
    "kind": "analysis",
    "structure": {"name": "lab_frame_3dof"},
    "measured": {"builtin": "lab_frame", "case": "base"},
    "validation": [{"case": "mass_0.654kg", "structure_options": {"case": "mass_0.654kg"},
                    "measured": {"builtin": "lab_frame", "case": "mass_0.654kg"}}],
    "parameters": {"names": ["kyy", "kxx", "krr"]},
    "points": {"initial": {}, "stiffer": {"ratios": {"kxx": 1.2}, "values": {"kyy": 9000.0}}},
    "sensitivity": {"rel_step": 1.0e-3},
    "sweep": {"structure.options.added_mass_kg": [0.0, 0.3]},
    "execution": {"progress": False},
}
TABLES = ("points", "parameters", "modes", "sensitivity", "identifiability", "parameter_correlation")


def _run(tmp_path, name, **changes):
    cfg = validate({**SMALL, "output": str(tmp_path / name), **changes})
    run_study(cfg, figures=False)
    return {t: pd.read_csv(tmp_path / name / f"{t}.csv") for t in TABLES}


def test_tables_hold_points_parameters_modes_and_sensitivities(tmp_path):
    t = _run(tmp_path, "a")
    points = t["points"]
    assert len(points) == 4 and set(points["label"]) == {"initial", "stiffer"}
    assert points["added_mass_kg"].tolist() == [0.0, 0.3, 0.0, 0.3]  # a swept option is a typed column
    assert (points["status"] == "ok").all() and (points["condition_number"] > 1).all()
    p = t["parameters"].set_index(["label", "added_mass_kg", "parameter"])
    assert p.loc[("stiffer", 0.0, "kxx"), "ratio"] == pytest.approx(1.2)
    assert p.loc[("stiffer", 0.0, "kyy"), "value"] == 9000.0
    modes = t["modes"]
    assert set(modes["case"]) == {"base", "mass_0.654kg"} and set(modes["pairing"]) == {"objective"}
    base = modes[(modes["label"] == "initial") & (modes["case"] == "base") & (modes["added_mass_kg"] == 0.0)]
    np.testing.assert_allclose(base["f_model_hz"], [3.589, 5.419, 7.851], atol=1e-3)  # documented initial model
    sens = t["sensitivity"]
    assert len(sens) == 4 * 3 * 3
    s = sens[(sens["label"] == "initial") & (sens["added_mass_kg"] == 0.0)].set_index(["parameter", "mode"])
    # f ~ sqrt(k): the y sway depends on kyy with S close to 1/2, the torsion on krr
    assert 0.3 < s.loc[("kyy", 1), "rel_sensitivity_frequency"] < 0.55
    assert s.loc[("krr", 3), "rel_sensitivity_frequency"] > 0.1
    assert abs(s.loc[("kxx", 1), "rel_sensitivity_frequency"]) < 0.05
    corr = t["parameter_correlation"]
    assert len(corr) == 4 * 9
    diag = corr[corr["parameter"] == corr["parameter_other"]]["correlation"]
    np.testing.assert_allclose(diag, 1.0, atol=1e-9)
    assert len(t["identifiability"]) == 4 * 3


def test_sensitivities_are_those_of_the_sensitivity_function(tmp_path):
    t = _run(tmp_path, "a", sweep={})
    model = make_model()
    problem = UpdatingProblem(model, measured("base"), parameters=model.parameters.subset(["kyy", "kxx", "krr"]))
    theta = problem.parameters.initial.copy()
    theta[0], theta[1] = 9000.0, 1.2 * theta[1]
    ref = sensitivity_matrix(problem, theta0=theta, rel_step=1e-3)
    sens = t["sensitivity"][t["sensitivity"]["label"] == "stiffer"]
    for j, name in enumerate(ref.parameters):
        rows = sens[sens["parameter"] == name].sort_values("mode")
        np.testing.assert_array_equal(rows["rel_sensitivity_frequency"], ref.frequency[:, j])
        np.testing.assert_array_equal(rows["rel_sensitivity_mac"], ref.mac[:, j])
    ident = t["identifiability"][t["identifiability"]["label"] == "stiffer"]
    np.testing.assert_array_equal(ident["singular_value"], ref.singular_values)


def test_widened_bounds_keep_a_step_at_the_upper_bound_forward(tmp_path):
    """At kxx's upper bound the default step goes backwards; with widen it goes forwards."""
    model = make_model()
    upper = model.parameters.by_name("kxx").upper
    point = {"top": {"values": {"kxx": upper}}}
    back = _run(tmp_path, "b", sweep={}, points=point)["sensitivity"]
    fwd = _run(tmp_path, "f", sweep={}, points=point, sensitivity={"rel_step": 1e-3, "widen": [0.5, 2.0]})["sensitivity"]
    problem = UpdatingProblem(model, measured("base"), parameters=model.parameters.subset(["kyy", "kxx", "krr"]))
    theta = problem.parameters.initial.copy()
    theta[1] = upper
    wide = problem.parameters.with_bounds({"kxx": (0.0, 2 * upper)})
    wide_problem = UpdatingProblem(model, measured("base"), parameters=wide)
    f0 = wide_problem.correlation_at(theta).f_model_hz
    step = theta.copy()
    step[1] *= 1.001
    expected = (wide_problem.correlation_at(step).f_model_hz - f0) / f0 / 1e-3
    got = fwd[fwd["parameter"] == "kxx"].sort_values("mode")["rel_sensitivity_frequency"].to_numpy()
    np.testing.assert_allclose(got, expected, rtol=1e-6)
    back_kxx = back[back["parameter"] == "kxx"].sort_values("mode")["rel_sensitivity_frequency"].to_numpy()
    assert not np.allclose(back_kxx, got, rtol=1e-9)  # a backward difference differs in the last digits
    np.testing.assert_allclose(back_kxx, got, rtol=1e-2)  # ... but not in the physics


def test_process_backend_resume_and_dask_give_the_same_tables(tmp_path):
    ref = _run(tmp_path, "serial")
    procs = _run(tmp_path, "procs", execution={"backend": "processes", "workers": 2, "progress": False})
    assert_same_tables(ref, procs)
    # remove one stored run, resume: only that run is computed again, tables identical
    parts = sorted((tmp_path / "serial" / "_runs").glob("*.json"))
    assert len(parts) == 4
    parts[1].unlink()
    cfg = validate({**SMALL, "output": str(tmp_path / "serial")})
    run_study(cfg, resume=True, figures=False)
    assert_same_tables(ref, {t: pd.read_csv(tmp_path / "serial" / f"{t}.csv") for t in TABLES})
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    try:
        dask = _run(tmp_path, "dask", execution={"backend": "dask", "scheduler": cluster.scheduler_address,
                                                 "progress": False})
    finally:
        cluster.close()
    assert_same_tables(ref, dask)


def test_report_options_do_not_change_run_ids():
    a = plan(validate(SMALL))
    b = plan(validate({**SMALL, "report": {"sensitivity": {"variants": ["x"]}, "modes": {"point": "stiffer"}}}))
    assert [s["run_id"] for s in a] == [s["run_id"] for s in b]
    c = plan(validate({**SMALL, "sensitivity": {"rel_step": 2e-3}}))
    assert not {s["run_id"] for s in a} & {s["run_id"] for s in c}


@pytest.mark.parametrize(
    "change, message",
    [
        ({"points": {"far": {"values": {"kyy": 1.0}}}}, "points.far: outside the bounds: kyy=1"),
        ({"points": {"p": {"ratios": {"kzz": 1.1}}}}, "points.p: \\['kzz'\\] are not parameters of the study"),
        ({"points": {"p": {"ratios": {"kyy": 1.1}, "values": {"kyy": 9000.0}}}}, "given both as values and as ratios"),
        ({"points": {}}, "give at least one point"),
        ({"pairings": ["type"]}, "pairings: 'type' needs the measured mode types"),
        ({"pairings": ["mac"]}, "pairings.0: Input should be 'objective' or 'type'"),
        ({"sensitivity": {"widen": [1.5, 2.0]}}, "widen must be \\[lo, hi\\] with 0 <= lo < 1 < hi"),
        ({"report": {"nonsense": {}}}, "report.nonsense: unknown analysis"),
    ],
)
def test_bad_inputs_fail_before_any_run(tmp_path, change, message):
    data = {**SMALL, "sweep": {}, "output": str(tmp_path / "bad"), **change}
    with pytest.raises(InputError, match=message):
        run_study(validate(data), figures=False)
    assert not list((tmp_path / "bad").glob("_runs/*.json"))


def test_cli_runs_an_analysis_config_and_report_redraws_its_figures(tmp_path):
    from framework.cli import main

    data = {**SMALL, "sweep": {}, "output": str(tmp_path / "cli"),
            "report": {"sensitivity": {}, "modes": {"point": "initial"}}}
    path = tmp_path / "analysis.yaml"
    path.write_text(yaml.safe_dump(data))
    assert main(["run", str(path), "--quiet"]) == 0
    out = tmp_path / "cli"
    for name in ("sensitivity.png", "parameter_correlation.png", "singular_values.png", "mode_errors.png"):
        (out / name).unlink()
    assert main(["report", str(out)]) == 0
    for name in ("sensitivity.png", "parameter_correlation.png", "singular_values.png", "frequencies.png",
                 "mode_errors.png"):
        assert (out / name).stat().st_size > 5_000, name
    summary = pd.read_csv(out / "sensitivity_summary.csv")
    top = summary[summary["label"] == "initial"].set_index("parameter")
    assert top.loc["kyy", "mode_of_max"] == "1st y" and top["rank"].min() == 1
    modes = pd.read_csv(out / "mode_summary.csv")
    assert (modes["matched"] == 3).all()


def test_comparison_takes_the_best_run_that_did_not_fail_of_each_model():
    from framework.report.analyses import comparison

    runs = pd.DataFrame({"run_id": list("abcd"), "label": "pso", "variant": ["x", "x", "y", "y"],
                         "structure": ["s1", "s1", "s2", "s2"], "swarm_size": 20, "seed": [0, 1, 0, 1],
                         "objective": [2.0, 1.0, 0.5, 3.0], "n_evaluations": 10,
                         "status": ["stalled", "stalled", "failed", "stalled"]})
    parameters = pd.DataFrame({"run_id": list("abcd"), "parameter": "k", "value": [1.0, 2.0, 3.0, 4.0]})
    modes = pd.DataFrame({"run_id": [r for r in "abcd" for _ in range(2)], "case": "base", "mode": [1, 2] * 4,
                          "mode_label": ["m1", "m2"] * 4, "f_measured_hz": 1.0, "f_model_hz": 1.01,
                          "error_pct": [1.0, -2.0] * 4, "mac": 0.99, "matched": True})
    out = comparison.tables({"runs": runs, "parameters": parameters, "modes": modes})
    best = out["comparison_runs"].set_index("model")
    assert best.loc["x", "run_id"] == "b" and best.loc["y", "run_id"] == "d"  # the failed run c is left out
    assert best.loc["x", "k"] == 2.0 and best.loc["y", "runs"] == 1
    assert best.loc["y", "structure"] == "s2" and "swarm_size" not in best  # only settings that differ
    summary = out["comparison_summary"].set_index("model")
    assert summary.loc["x", "max_abs_error_pct"] == 2.0 and summary.loc["x", "matched"] == 2
    assert len(out["comparison"]) == 4
