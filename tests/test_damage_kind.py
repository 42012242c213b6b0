"""Run kind ``damage`` (beam damage study): tables, the source's baseline-difference
procedure, reproducibility in serial, process, resumed and Dask execution, and run
identities that do not depend on report options."""

import numpy as np
import pandas as pd
import pytest

from framework.core.errors import InputError
from framework.study.config import validate
from framework.study.plan import plan
from framework.study.runner import run_study
from tests.tables import assert_same_tables

TINY = {
    "study": "tiny_damage",
    "kind": "damage",
    "runs": 1,
    "noise_pct": 3.0,
    "pso": {"evaluations": 200, "swarm_size": 10},
    "nsga2": {"pop_size": 16, "generations": 3},
    "polish_evaluations": 60,
    "lcurve": {"tau_min": 1.0e-6, "tau_max": 1.0, "per_decade": 1},
    "execution": {"progress": False},
}
TABLES = ("runs", "states", "elements", "pareto", "lcurve", "comparison", "damage_indices", "lcurve_choice")


def _run(tmp_path, name, **changes):
    cfg = validate({**TINY, "output": str(tmp_path / name), **changes})
    run_study(cfg, figures=False)
    return {t: pd.read_csv(tmp_path / name / f"{t}.csv") for t in TABLES}


def test_tables_columns_and_the_baseline_difference_of_the_source(tmp_path):
    t = _run(tmp_path, "a")
    runs, states, elements = t["runs"], t["states"], t["elements"]
    assert sorted(runs["procedure"]) == ["nsga2", "single_objective", "tikhonov"]
    assert (runs["status"] == "ok").all() and (runs["noise_pct"] == 3.0).all()
    assert set(states["method"]) == {"soo", "soo+sm (ours)", "pso (ours)", "pso+sm (ours)", "sm (ours)", "nsga2",
                                     "nsga2+sm (ours)", "pso_tikhonov", "pso_tikhonov+sm (ours)"}
    # source procedure: estimate = 1 - (r_intact - r_state), the intact update of the same run
    soo = elements[(elements["method"] == "soo") & (elements["state"] == "state2")].sort_values("element")
    intact = elements[(elements["method"] == "pso (ours)") & (elements["state"] == "intact")].sort_values("element")
    np.testing.assert_allclose(soo["baseline_ratio"].to_numpy(), intact["updated_ratio"].to_numpy())
    np.testing.assert_allclose(soo["estimated_ratio"], 1.0 - (soo["baseline_ratio"] - soo["updated_ratio"]))
    np.testing.assert_allclose(soo["truth_ratio"], [1, 1, 0.9, 1, 1, 0.85, 1, 1, 1, 1])
    np.testing.assert_allclose(soo["error"], soo["estimated_ratio"] - soo["truth_ratio"])
    # a polish never ends worse than the search it starts from (unregularized Pi)
    obj = states.set_index(["method", "state"])["objective"]
    for state in ("state1", "state2"):
        assert obj[("pso+sm (ours)", state)] <= obj[("pso (ours)", state)]
        assert obj[("nsga2+sm (ours)", state)] <= obj[("nsga2", state)]
    # one corner per state, the chosen tau is the one the Tikhonov methods used
    lc = t["lcurve"]
    assert len(lc) == 2 * 7 and lc.groupby("state")["chosen"].sum().eq(1).all()
    choice = t["lcurve_choice"].set_index("state")["tau"]
    tik = states[states["method"] == "pso_tikhonov"].set_index("state")["tau"]
    assert choice.to_dict() == tik.to_dict()
    assert t["pareto"]["chosen"].sum() == 1
    cmp = t["comparison"]
    assert {"mean_error", "max_error", "false_detections", "missed", "threshold"} <= set(cmp.columns)
    assert len(t["damage_indices"]) == len(elements)


def test_process_backend_resume_and_dask_give_the_same_tables(tmp_path):
    ref = _run(tmp_path, "serial")
    procs = _run(tmp_path, "procs", execution={"backend": "processes", "workers": 2, "progress": False})
    assert_same_tables(ref, procs)
    parts = sorted((tmp_path / "serial" / "_runs").glob("*.json"))
    assert len(parts) == 3
    parts[0].unlink()
    run_study(validate({**TINY, "output": str(tmp_path / "serial")}), resume=True, figures=False)
    assert_same_tables(ref, {t: pd.read_csv(tmp_path / "serial" / f"{t}.csv") for t in TABLES})
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    try:
        dask = _run(tmp_path, "dask", execution={"backend": "dask", "scheduler": cluster.scheduler_address,
                                                 "progress": False})
    finally:
        cluster.close()
    assert_same_tables(ref, dask)


def test_report_options_keep_run_ids_and_settings_change_only_their_runs():
    a = plan(validate(TINY))
    b = plan(validate({**TINY, "report": {"damage_summary": {"threshold": 0.1, "figure_noise": [3.0]}}}))
    assert [s["run_id"] for s in a] == [s["run_id"] for s in b]
    # the L-curve grid belongs to the Tikhonov runs only
    c = plan(validate({**TINY, "lcurve": {"tau_min": 1.0e-8, "tau_max": 1.0, "per_decade": 1}}))
    changed = {s["label"] for s in c} - {s["label"] for s in c if s["run_id"] in {x["run_id"] for x in a}}
    assert changed == {"tikhonov"}
    swept = plan(validate({**TINY, "sweep": {"noise_pct": [1.0, 3.0]}}))
    assert len(swept) == 6 and {s["columns"]["noise_pct"] for s in swept} == {1.0, 3.0}


@pytest.mark.parametrize(
    "change, message",
    [
        ({"procedures": ["annealing"]}, "procedures.0: Input should be"),
        ({"lcurve": {"tau_min": 1.0, "tau_max": 0.1}}, "tau_max must be finite and above tau_min"),
        ({"noise_pct": -1.0}, "noise_pct: Input should be greater than or equal to 0"),
        ({"report": {"damage_summary": {"threshold": 2.0}}}, "threshold: give a number in \\(0, 1\\)"),
    ],
)
def test_bad_inputs_name_the_field(tmp_path, change, message):
    with pytest.raises(InputError, match=message):
        run_study(validate({**TINY, "output": str(tmp_path / "bad"), **change}), figures=False)
