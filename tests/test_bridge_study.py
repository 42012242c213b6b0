"""Bridge studies (SPEC 6): the summary of the updating runs, the initial models of four
cable discretisations (run kind ``analysis``), and the consistency of the committed configs."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from framework.core.errors import InputError
from framework.report.analyses import updating_summary
from framework.structures import bridge
from framework.study.config import load, validate
from framework.study.runner import run_study

ROOT = Path(__file__).resolve().parents[1]
NAMES = list(bridge.PARAMETER_NAMES)


def _fake_runner_tables():
    runs, params, modes, extra = [], [], [], []
    ratios = {
        "sm_1.00": [1.0, 1.1, 0.8, 0.76, 1.19, 1.3],
        "sm_0.92": [1.0, 1.1, 0.8, 0.77, 1.19, 1.3],
        "pso": [1.0, 1.1, 0.8, 0.76, 1.2, 1.29],
        "snt": [0.95, 1.05, 0.85, 0.7, 1.25, 1.0],
    }
    for k, (label, r) in enumerate(ratios.items()):
        run_id = f"r{k}"
        runs.append({"run_id": run_id, "label": label, "algorithm": label.split("_")[0], "seed": 0,
                     "objective": 0.0023 + k * 1e-5, "n_evaluations": 70, "condition_number": 6.9,
                     "status": "converged"})
        for name, value in sorted(zip(NAMES, r)):  # the store sorts the rows by parameter name
            params.append({"run_id": run_id, "label": label, "algorithm": label.split("_")[0], "seed": 0,
                           "parameter": name, "initial": 1.0, "lower": 0.6, "upper": 1.3, "value": value,
                           "ratio": value, "normalized": (value - 0.6) / 0.7})
        for j in range(8):
            modes.append({"run_id": run_id, "label": label, "algorithm": label.split("_")[0], "case": "base",
                          "mode": j + 1, "error_pct": 1.0 + k, "mac": 0.999})
    best = ratios["snt"]
    minima = [
        {"minimum": 1, "x": [(v - 0.6) / 0.7 for v in best], "theta": best, "raw_objective": 0.0023,
         "derated_objective": 0.0023, "artefact": False, "distance_to_previous": [], "n_evaluations": 900},
        {"minimum": 2, "x": [0.4] * 6, "theta": [0.88] * 6, "raw_objective": 0.01, "derated_objective": 0.02,
         "artefact": True, "distance_to_previous": [0.5], "n_evaluations": 800},
    ]
    extra.append({"run_id": "r3", "label": "snt", "key": "minima", "value": json.dumps(minima)})
    extra.append({"run_id": "r3", "label": "snt", "key": "niche_radius", "value": json.dumps(0.5)})
    return {name: pd.DataFrame(rows) for name, rows in
            (("runs", runs), ("parameters", params), ("modes", modes), ("extra", extra))}


def test_updating_summary_reports_sm_spread_and_snt_minima(tmp_path):
    tables = _fake_runner_tables()
    out = updating_summary.tables(tables, starts="sm", spread="pso")
    assert out["sm_starts"]["label"].tolist() == ["sm_0.92", "sm_1.00"]
    assert out["sm_starts"]["max_ratio_distance_between_starts"].iloc[0] == pytest.approx(0.01)
    spread = out["pso_spread"].set_index("quantity")
    assert spread.loc["K_cable", "count"] == 1 and spread.loc["T_Cab1", "mean"] == pytest.approx(1.2)
    snt = out["snt_minima"]
    assert list(snt["minimum"]) == [1, 2]
    assert snt["artefact_of_niche_radius"].tolist() == [False, True]
    assert snt["on_niche_boundary"].tolist() == [False, True]
    # the minima's vectors are in the problem's order, recovered although the table is sorted
    assert snt["K_y_deck"].tolist() == pytest.approx([0.95, 0.88]) and snt["K_cable"].iloc[0] == pytest.approx(0.7)
    assert out["updated_modes_best_run"]["run_id"].unique().tolist() == ["r0"]
    written = updating_summary.figures({**tables, **out}, tmp_path)
    assert [p.name for p in written] == ["updated_ratios.png", "updated_errors.png"]
    assert all(p.stat().st_size > 5_000 for p in written)


def test_minima_order_can_be_given_when_the_best_point_is_ambiguous():
    tables = _fake_runner_tables()
    minima = json.loads(tables["extra"]["value"].iloc[0])
    minima[0]["x"] = [0.5] * 6  # matches no parameter of the run's best point
    tables["extra"].loc[0, "value"] = json.dumps(minima)
    with pytest.raises(ValueError, match="parameter_order"):
        updating_summary.tables(tables)
    out = updating_summary.tables(tables, parameter_order=NAMES)
    assert out["snt_minima"]["K_y_deck"].iloc[0] == pytest.approx(0.95)


def test_initial_models_show_the_mode_lost_by_one_element_cables(tmp_path):
    """Run kind ``analysis`` on the bridge: 1- and 4-element cables at the initial point."""
    cfg = load(ROOT / "studies" / "bridge_analysis.yaml")
    data = cfg.model_dump(mode="json")
    data.update(output=str(tmp_path / "bridge"), sensitivity=None, report={},
                variants={"cables_1": {"structure.options.cable_elements": 1, "points": {"initial": {}}},
                          "cables_4": {"points": {"initial": {}}}})
    data["execution"]["progress"] = False
    run_study(validate(data), figures=False)
    modes = pd.read_csv(tmp_path / "bridge" / "modes.csv")
    assert set(modes["cable_elements"]) == {1, 4}  # a structure option is a typed column
    peak = modes[(modes["case"] == "peak") & (modes["pairing"] == "type") & (modes["cable_elements"] == 4)]
    np.testing.assert_allclose(peak["f_measured_hz"], bridge.MEASURED_PEAK_HZ)
    modes = modes[modes["case"] == "base"]
    by_type = modes[modes["pairing"] == "type"].set_index(["cable_elements", "mode"])
    four = by_type.loc[4]
    assert np.all(np.abs(four["error_pct"]) < 11.0)
    assert (four["mode_type"] == four["measured_type"]).all()
    assert four.loc[2, "cable_energy"] > four.loc[3, "cable_energy"]  # the cable-coupled 2nd vertical mode
    np.testing.assert_allclose(four["design_model_hz"], bridge.DESIGN_MODEL_HZ)
    assert by_type.loc[(1, 2), "f_model_hz"] > 2.5  # nearest vertical mode is the 2.78 Hz pylon mode
    by_mac = modes[modes["pairing"] == "objective"].set_index(["cable_elements", "mode"])
    assert not by_mac.loc[(1, 1), "matched"] and by_mac.loc[4, "matched"].all()


def test_committed_updated_point_is_the_sm_result_of_the_cable_study():
    """studies/bridge_analysis.yaml's updated point = SM of studies/bridge_cables.yaml (4 elements)."""
    cfg = load(ROOT / "studies" / "bridge_analysis.yaml")
    ratios = cfg.points["updated"].ratios
    params = pd.read_csv(ROOT / "results" / "bridge" / "cables" / "parameters.csv")
    sm4 = params[params["cable_elements"] == 4].set_index("parameter")["ratio"]
    # a regenerated cable study lands within ~1e-9 of the stored point: OpenSees' eigen solver
    # keeps state between calls in a process, so SM's last digits depend on what ran before
    for name in NAMES:
        assert ratios[name] == pytest.approx(sm4[name], rel=1e-8), name


def test_bridge_analysis_gives_the_same_tables_on_dask_and_after_resume(tmp_path):
    """The ported study (kind analysis, OpenSees fast path): serial = Dask = resumed."""
    distributed = pytest.importorskip("distributed")
    data = load(ROOT / "studies" / "bridge_analysis.yaml").model_dump(mode="json")
    data.update(variants={}, validation=[], pairings=["objective"], report={})
    data["execution"]["progress"] = False
    names = ("points", "modes", "sensitivity", "identifiability", "parameter_correlation")

    def tables(name, **execution):
        cfg = validate({**data, "output": str(tmp_path / name), "execution": {**data["execution"], **execution}})
        run_study(cfg, figures=False)
        return {t: pd.read_csv(tmp_path / name / f"{t}.csv").drop(columns="wall_s", errors="ignore") for t in names}

    serial = tables("serial")
    assert len(serial["points"]) == 2 and len(serial["sensitivity"]) == 2 * 6 * 8
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    try:
        dask = tables("dask", backend="dask", scheduler=cluster.scheduler_address)
    finally:
        cluster.close()
    next((tmp_path / "serial" / "_runs").glob("*.json")).unlink()
    cfg = validate({**data, "output": str(tmp_path / "serial")})
    run_study(cfg, resume=True, figures=False)
    resumed = {t: pd.read_csv(tmp_path / "serial" / f"{t}.csv").drop(columns="wall_s", errors="ignore") for t in names}
    for name in names:
        pd.testing.assert_frame_equal(serial[name], dask[name], check_exact=True)
        pd.testing.assert_frame_equal(serial[name], resumed[name], check_exact=True)


def test_sm_starts_are_compared_per_method_and_pso_spread_per_label():
    tables = _fake_runner_tables()
    runs = tables["runs"]
    runs["method"] = ["trust_region", "pseudo_inverse", None, None]
    runs.loc[runs["label"] == "pso", "label"] = "pso_stall10 (ours)"
    for name in ("parameters", "modes"):
        tables[name].loc[tables[name]["run_id"] == "r2", "label"] = "pso_stall10 (ours)"
    out = updating_summary.tables(tables, starts="sm", spread="pso")
    starts = out["sm_starts"].set_index("label")
    assert set(starts["method"]) == {"trust_region", "pseudo_inverse"}
    assert (starts["max_ratio_distance_between_starts"] == 0.0).all()  # one start per method here
    spread = out["pso_spread"]
    assert set(spread["label"]) == {"pso_stall10 (ours)"}
    assert "n_evaluations" in set(spread["quantity"])
    by_label = out["updated_modes_by_label"]
    assert sorted(by_label["label"].unique()) == ["pso_stall10 (ours)", "sm_0.92", "sm_1.00", "snt"]


def test_choices_table_comes_from_the_model_and_the_config():
    from framework.report.analyses import choices
    from framework.study.structure_hooks import with_structure_choices

    points = pd.DataFrame({"study": ["s", "s"], "variant": ["old", "new"], "lateral_restraint": ["guided", None],
                           "deck_section": ["slab_overhangs", None], "cable_elements": [4, 4]})
    items = [{"item": "SM method", "value": "pseudo-inverse", "origin": "source-given", "reason": "SPEC 4"}]
    # the study layer passes the structure's modelling choices from its descriptor
    report = with_structure_choices({"choices": {"structure": {"name": "bridge", "variant": "new"}, "items": items}})
    new = choices.tables({"points": points}, **report["choices"])["choices"]
    old = choices.tables({"points": points}, structure={"name": "bridge", "variant": "old"},
                         modelling_choices=report["choices"]["modelling_choices"])["choices"]
    assert list(new.columns) == ["study", "item", "value", "origin", "reason"]
    assert set(new["origin"]) == {"source-given", "our assumption"} and (new["study"] == "s").all()
    lateral = {name: t.set_index("item").loc["bearing lateral restraint", "value"] for name, t in
               (("new", new), ("old", old))}
    assert lateral["new"].startswith("rigid") and lateral["old"].startswith("the vertical stiffness")
    mass = new.set_index("item").loc["deck mass", "value"]
    assert mass.startswith(f"{bridge.deck_mass_per_m()[0]:.1f} kg/m")
    assert new["item"].iloc[-1] == "SM method"
    with pytest.raises(InputError, match="origin"):
        choices.tables({}, items=[{**items[0], "origin": "guess"}])
    bridge_choices = report["choices"]["modelling_choices"]
    with pytest.raises(InputError, match="several variants"):
        choices.tables({"points": points}, structure={"name": "bridge"}, modelling_choices=bridge_choices)
    with pytest.raises(InputError, match="differs"):
        choices.tables({"points": points.assign(variant="one")}, structure={"name": "bridge"},
                       modelling_choices=bridge_choices)
    with pytest.raises(InputError, match="'beam' documents no modelling choices"):
        with_structure_choices({"choices": {"structure": {"name": "beam"}}})
    with pytest.raises(InputError, match="not a built-in structure"):
        with_structure_choices({"choices": {"structure": {"name": "nowhere"}}})



def test_committed_initial_frequencies_before_and_after_against_the_source():
    """results/bridge/analysis/frequencies.csv: the model before issue 15 had both lateral
    modes 8-12 % below the source's initial model; the revised model is within 7.3 % there
    and within 10.2 % on every mode (the 5th vertical mode)."""
    freq = pd.read_csv(ROOT / "results" / "bridge" / "analysis" / "frequencies.csv").set_index("mode")
    np.testing.assert_allclose(freq["design_model_hz"], bridge.DESIGN_MODEL_HZ)
    np.testing.assert_allclose(freq["f_before_issue15_hz"], [1.571, 1.944, 4.033, 4.622, 5.013, 6.834, 7.329, 9.175],
                               atol=6e-4)
    assert (freq.loc[[4, 5], "dev_before_issue15_pct"] < -8.0).all()
    assert (freq.loc[[4, 5], "dev_cables_4_pct"].abs() < 7.3).all()
    assert freq["dev_cables_4_pct"].abs().max() < 10.2
    assert freq["dev_cables_4_pct"].abs().max() == pytest.approx(-freq.loc[7, "dev_cables_4_pct"])


def test_bridge_study_replication_settings_follow_the_source():
    """studies/bridge.yaml: SM as the pseudo-inverse iteration from 1.00, 0.92 and 1.11, PSO
    swarm 20 for exactly 200 generations (no stall stop), 10 runs, SNT for 4 minima with a
    total budget; our variants are labelled (ours)."""
    cfg = load(ROOT / "studies" / "bridge.yaml")
    algs = cfg.algorithms
    given = {k: a.model_dump(mode="json")["settings"] for k, a in algs.items()}  # the settings as written
    pinv = {k: a for k, a in algs.items() if given[k].get("method") == "pseudo_inverse"}
    assert sorted(a.settings.start_factor for a in pinv.values()) == [0.92, 1.0, 1.11]
    assert all(not k.endswith(" (ours)") for k in pinv)
    assert all(k.endswith(" (ours)") for k in algs if given[k].get("method") == "trust_region")
    pso = algs["pso"]
    assert given["pso"] == {"swarm_size": 20, "factor": 0.75}
    assert pso.settings.swarm_size == 20 and pso.settings.factor == 0.75 and pso.settings.c1 == 1.5
    assert pso.budget == {"max_iterations": 200, "stall_tolerance": 0.0} and (pso.runs or cfg.runs) == 10
    assert cfg.budget.max_evaluations >= 200 * 20 and cfg.budget.target_objective < 1e-3  # 2.7e-3 is the floor
    snt = algs["snt"]
    assert snt.settings.n_minima == 4 and "max_iterations" not in snt.budget
    assert snt.budget["max_evaluations"] >= 4 * 200 * 20
