"""Global-local hybrids and the parallel multi-start of the sensitivity method."""

import json
from dataclasses import dataclass
from itertools import combinations

import numpy as np
import pandas as pd
import pytest

from framework.core.errors import InputError
from framework.core.parameters import Parameter, ParameterSet
from framework.measured.modes import MeasuredModes
from framework.models.base import ModalResult
from framework.optimizers import OPTIMIZERS, Budget, run_optimizer
from framework.optimizers.hybrid import distinct_best
from framework.optimizers.sampling import sample
from framework.structures.lab_frame.model import make_model, measured
from framework.updating.objectives import ObjectiveSpec
from framework.updating.problem import UpdatingProblem


def lab_problem() -> UpdatingProblem:
    return UpdatingProblem(make_model(), measured())


def hybrid(algorithm: str, settings: dict | None = None, global_evaluations: int = 400, **extra) -> dict:
    return {"global": {"algorithm": algorithm, "settings": settings or {}, "max_evaluations": global_evaluations},
            **extra}


# ---- hybrid ---------------------------------------------------------------------------------
GLOBAL = {
    "pso": {"swarm_size": 10},
    "ga": {"pop_size": 10},
    "annealing": {"max_iterations": 20},
    "snt": {"n_minima": 2, "pso": {"swarm_size": 10}},
    "screening": {"sampler": "latin_hypercube"},
}


@pytest.mark.parametrize("algorithm", sorted(GLOBAL))
def test_hybrid_keeps_both_phases_within_the_total_budget(algorithm):
    budget = Budget(max_evaluations=900)
    r = run_optimizer("hybrid", lab_problem(), 2, budget, **hybrid(algorithm, GLOBAL[algorithm], n_candidates=3))
    cols = r.extra["run_columns"]
    assert r.n_evaluations <= budget.max_evaluations and r.history.shape == (r.n_evaluations,)
    assert 0 < cols["global_evaluations"] <= 400 and cols["local_evaluations"] > 0
    assert cols["global_evaluations"] + cols["local_evaluations"] == r.n_evaluations
    g = r.extra["global"]
    assert g["algorithm"] == algorithm and g["objective"] == cols["global_objective"]
    cands = [r.extra[f"candidate_{i}"] for i in range(1, cols["n_polished"] + 1)]
    assert 1 <= len(cands) <= 3 and cands[0]["global_objective"] == pytest.approx(g["objective"])
    for c in cands:  # a polish starts at its candidate and never ends worse
        assert c["polished_objective"] <= c["global_objective"]
    assert r.objective == pytest.approx(min(c["polished_objective"] for c in cands), rel=1e-12)
    assert r.extra[f"candidate_{cols['best_candidate']}"]["polished_objective"] == r.objective
    assert r.objective <= g["objective"]
    json.dumps(r.extra, allow_nan=True)


def test_hybrid_candidates_are_distinct_and_best_first():
    r = run_optimizer("hybrid", lab_problem(), 0, Budget(max_evaluations=2000),
                      **hybrid("screening", {}, 512, n_candidates=4, min_distance=0.2))
    cands = [r.extra[f"candidate_{i}"] for i in range(1, 5)]
    values = [c["global_objective"] for c in cands]
    assert values == sorted(values)
    for a, b in combinations(cands, 2):
        assert np.linalg.norm(np.subtract(a["x_start"], b["x_start"])) / np.sqrt(6) > 0.2
    # the screening sample is the run's Sobol sample: its best point is the first candidate
    X = sample(512, 6, 0, "sobol")
    best = X[np.argmin(lab_problem().objective(X))]
    np.testing.assert_allclose(cands[0]["x_start"], best, rtol=0, atol=0)


def test_hybrid_caps_each_polish_and_refines_the_best_polished_points():
    budget = Budget(max_evaluations=1200)
    r = run_optimizer("hybrid", lab_problem(), 3, budget,
                      **hybrid("screening", {}, 300, n_candidates=4, max_evaluations_per_candidate=40, refine=2))
    cols = r.extra["run_columns"]
    cands = [r.extra[f"candidate_{i}"] for i in range(1, cols["n_polished"] + 1)]
    assert all(c["n_evaluations"] <= 40 for c in cands[:4]) and not any("refines" in c for c in cands[:4])
    first = sorted(cands[:4], key=lambda c: c["polished_objective"])
    refined = cands[4:]
    # refinements continue the best polished points in order, from where they ended; the first
    # is given every evaluation left, the next one runs only on what the first left over
    assert 1 <= len(refined) <= 2
    assert [c["refines"] for c in refined] == [c["candidate"] for c in first[: len(refined)]]
    for c in refined:
        np.testing.assert_array_equal(c["x_start"], r.extra[f"candidate_{c['refines']}"]["x_polished"])
        assert c["polished_objective"] <= r.extra[f"candidate_{c['refines']}"]["polished_objective"]
    assert refined[0]["n_evaluations"] > 40
    assert cols["global_evaluations"] + cols["local_evaluations"] == r.n_evaluations <= 1200
    assert r.objective == min(c["polished_objective"] for c in cands)
    assert r.extra[f"candidate_{cols['best_candidate']}"]["polished_objective"] == r.objective


def test_distinct_best_picks_in_order_and_skips_near_points():
    X = np.array([[0.0, 0.0], [0.05, 0.0], [1.0, 1.0], [0.5, 0.5], [0.9, 1.0]])
    values = np.array([1.0, 0.5, 3.0, np.nan, 2.0])
    # 1 (0.5) first; 0 is within 0.05 / sqrt(2) of it; then 4 (2.0); 2 is 0.07 from 4; NaN never
    assert distinct_best(X, values, 5, 0.1) == [1, 4]
    assert distinct_best(X, values, 5, 0.0) == [1, 0, 4, 2]
    assert distinct_best(X, values, 1, 0.1) == [1]


def test_hybrid_budget_is_shared_and_enforced():
    budget = Budget(max_evaluations=460)
    r = run_optimizer("hybrid", lab_problem(), 1, budget, **hybrid("pso", {"swarm_size": 10}, 400, n_candidates=3))
    assert r.n_evaluations <= 460
    assert r.extra["run_columns"]["local_evaluations"] <= 60
    with pytest.raises(InputError, match=r"global.max_evaluations \(400\) must be below the run's max_evaluations"):
        run_optimizer("hybrid", lab_problem(), 1, Budget(max_evaluations=400), **hybrid("pso"))


@pytest.mark.parametrize("settings, message", [
    (hybrid("pso", {"swarm_size": 1}), r"global.settings \(pso\).swarm_size: Input should be greater than or equal"),
    (hybrid("pso", {"swarm_sise": 10}), r"global.settings \(pso\).swarm_sise: unknown key"),
    (hybrid("nsga2"), r"global_phase.algorithm|global.algorithm"),
    (hybrid("pso", local={"settings": {"x0": [0.5] * 6}}), r"\['x0'\] are set by the hybrid"),
    (hybrid("pso", local={"settings": {"diff_step": -1}}), r"local.settings \(sm\).diff_step"),
    ({"local": {}}, r"global"),
])
def test_hybrid_settings_are_checked(settings, message):
    with pytest.raises(Exception, match=message):
        OPTIMIZERS["hybrid"].settings.model_validate(settings, strict=True)


def test_hybrid_settings_dump_by_their_config_names():
    dumped = OPTIMIZERS["hybrid"].settings.model_validate(hybrid("pso")).model_dump(mode="json")
    assert set(dumped) == {"global", "local", "n_candidates", "min_distance", "max_evaluations_per_candidate",
                           "refine"}
    assert dumped["global"]["settings"]["swarm_size"] == 20 and "x0" not in dumped["local"]["settings"]
    assert OPTIMIZERS["hybrid"].settings.model_validate(dumped, strict=True).model_dump(mode="json") == dumped


def test_hybrid_in_a_study_writes_phase_columns_and_candidate_rows(tmp_path):
    from framework.study.config import validate
    from framework.study.runner import run_study

    cfg = validate({
        "study": "hyb", "structure": {"name": "lab_frame_3dof"}, "measured": {"builtin": "lab_frame"},
        "budget": {"max_evaluations": 700},
        "algorithms": {"hybrid_pso_sm": {"algorithm": "hybrid", "settings": hybrid("pso", {"swarm_size": 10}, 300)}},
        "runs": 1, "seed": 0, "execution": {"progress": False}, "output": str(tmp_path / "out"),
    })
    run_study(cfg, figures=False)
    runs = pd.read_csv(tmp_path / "out" / "runs.csv")
    for col in ("global_objective", "global_evaluations", "local_evaluations", "n_polished", "best_candidate",
                "global_algorithm", "global_settings_swarm_size", "global_max_evaluations", "n_candidates"):
        assert col in runs, col
    row = runs.iloc[0]
    assert row["global_evaluations"] + row["local_evaluations"] == row["n_evaluations"] <= 700
    assert row["objective"] <= row["global_objective"]
    extra = pd.read_csv(tmp_path / "out" / "extra.csv")
    assert "run_columns" not in set(extra["key"])
    cand = json.loads(extra.set_index("key").loc["candidate_1", "value"])
    assert {"x_start", "global_objective", "polished_objective", "n_evaluations"} <= set(cand)


# ---- multi-start ----------------------------------------------------------------------------
def _multistart(runner=None, **settings):
    s = {"n_starts": 6, "batch_size": 2, **settings}
    return run_optimizer("multistart", lab_problem(), 5, Budget(max_evaluations=900), runner=runner, **s)


def _same(a, b):
    assert a.status == b.status and a.n_evaluations == b.n_evaluations and a.n_iterations == b.n_iterations
    np.testing.assert_array_equal(a.x_best, b.x_best)
    assert a.objective == b.objective
    np.testing.assert_array_equal(a.history, b.history)
    assert a.extra == b.extra


def test_multistart_is_identical_on_serial_and_process_runners():
    from framework.execution.parallel import ProcessRunner

    serial = _multistart()
    assert serial.extra["run_columns"]["n_starts_run"] == 6 and serial.n_evaluations <= 900
    with ProcessRunner(2) as runner:
        _same(serial, _multistart(runner))
    with ProcessRunner(1) as runner:  # the worker count changes nothing
        _same(serial, _multistart(runner))


def test_multistart_is_identical_on_dask():
    distributed = pytest.importorskip("distributed")
    from framework.execution.parallel import DaskRunner

    serial = _multistart()
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    try:
        with distributed.Client(cluster) as client:
            _same(serial, _multistart(DaskRunner(client)))
    finally:
        cluster.close()


def test_multistart_starts_budget_and_records():
    r = _multistart(include_initial=True, early_stop=False)
    starts = [r.extra[f"start_{i}"] for i in range(1, 7)]
    np.testing.assert_allclose(starts[0]["x_start"], lab_problem().x_initial)
    np.testing.assert_allclose([s["x_start"] for s in starts[1:]], sample(6, 6, 5, "sobol")[1:])
    assert sum(s["n_evaluations"] for s in starts) == r.n_evaluations <= 900
    assert all(s["n_evaluations"] <= s["budget"] for s in starts)
    assert r.objective == min(s["objective"] for s in starts)
    assert r.extra["run_columns"]["best_start"] == 1 + int(np.argmin([s["objective"] for s in starts]))
    tight = run_optimizer("multistart", lab_problem(), 5, Budget(max_evaluations=60), n_starts=6, batch_size=2,
                          min_evaluations_per_start=20)
    assert tight.n_evaluations <= 60 and tight.status == "budget"
    assert [tight.extra[f"start_{i}"]["budget"] for i in (1, 2)] == [20, 20]
    assert [tight.extra[f"start_{i}"]["status"] for i in (5, 6)] == ["not_run", "not_run"]


@dataclass(frozen=True)
class Wells:
    """Residuals r = [t_j - 0.8, 0.3 sin(5 pi t_j)] (j = 1, 2) as relative frequency errors:
    a local minimum near every t_j in {0, 0.2, 0.4, 0.6} and the global one, 0, at t = (0.8, 0.8)."""

    @property
    def parameters(self):
        return ParameterSet([Parameter("t1", 0.1, 0.0, 1.0), Parameter("t2", 0.1, 0.0, 1.0)])

    @property
    def dofs(self):
        return ("a",)

    def modal(self, theta):
        t = np.array([theta["t1"], theta["t2"]])
        r = np.concatenate([t - 0.8, 0.3 * np.sin(5 * np.pi * t)])
        return ModalResult(np.arange(1.0, 5.0) * (1.0 + r), np.zeros((1, 4)), ("a",))


@pytest.mark.parametrize("seed", [0, 2, 5])
def test_early_stopping_keeps_the_start_that_is_best(seed):
    """Many local minima; the best start comes in a later batch than the incumbent's: early
    stopping ends some starts but not the one that gives the result."""
    problem = UpdatingProblem(Wells(), MeasuredModes(frequencies_hz=np.arange(1.0, 5.0)),
                              objective=ObjectiveSpec(pairing="order", use_shapes=False))
    budget = Budget(max_evaluations=2000, target_objective=None)
    full = run_optimizer("multistart", problem, seed, budget, n_starts=12, batch_size=3, early_stop=False)
    early = run_optimizer("multistart", problem, seed, budget, n_starts=12, batch_size=3)
    best = full.extra["run_columns"]["best_start"]
    assert best > 3  # not in the first batch, whose best is the first incumbent
    assert early.extra["run_columns"]["best_start"] == best and early.objective == full.objective
    assert early.extra["run_columns"]["n_stopped_early"] >= 1 and early.n_evaluations < full.n_evaluations
    for i in range(1, 13):
        s = early.extra[f"start_{i}"]
        if s["status"] == "stopped_early":  # stopped only above the threshold, after the grace period
            assert s["objective"] > s["stop_threshold"] and s["n_evaluations"] >= 3 * (2 + 1)
            assert full.extra[f"start_{i}"]["objective"] > full.objective


def test_multistart_settings_are_checked():
    with pytest.raises(Exception, match=r"\['start'\] are set by the multi-start"):
        OPTIMIZERS["multistart"].settings.model_validate({"local": {"start": "random"}}, strict=True)
    with pytest.raises(Exception, match="stop_factor"):
        OPTIMIZERS["multistart"].settings.model_validate({"stop_factor": 0.5}, strict=True)


# ---- failed evaluations ---------------------------------------------------------------------
def _holey(kxx_limit: float, **objective) -> UpdatingProblem:
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import fault_models

    return UpdatingProblem(fault_models.make_holey(kxx_limit), measured(),
                           objective=ObjectiveSpec(**objective) if objective else None)


SETTINGS = {"hybrid": hybrid("pso", {"swarm_size": 10}, 100), "multistart": {"n_starts": 4, "batch_size": 2}}


@pytest.mark.parametrize("algorithm", sorted(SETTINGS))
def test_failed_points_are_never_the_result(algorithm):
    everywhere = run_optimizer(algorithm, _holey(15000.0), 0, Budget(max_evaluations=200), **SETTINGS[algorithm])
    assert everywhere.status == "failed" and np.isnan(everywhere.objective)
    assert everywhere.n_failed == everywhere.n_evaluations > 0
    problem = _holey(21000.0, failure_penalty=1e-9)
    r = run_optimizer(algorithm, problem, 2, Budget(max_evaluations=300), **SETTINGS[algorithm])
    assert r.n_failed > 0 and r.status not in ("failed", "target") and r.objective > 1e-9
    assert problem.evaluate(r.x_best[None, :]).ok[0]


def test_sm_x_scale_setting():
    """x_scale "unit" is least_squares' default for trf (identical runs); "jac" scales by the Jacobian."""
    problem, budget = lab_problem(), Budget(max_evaluations=400)
    default = run_optimizer("sm", problem, 1, budget, start="random")
    unit = run_optimizer("sm", problem, 1, budget, start="random", x_scale="unit")
    np.testing.assert_array_equal(unit.history, default.history)
    jac = run_optimizer("sm", problem, 1, budget, start="random", x_scale="jac")
    assert jac.objective < 1e-4 and jac.n_evaluations <= 400
    with pytest.raises(Exception, match="x_scale"):
        OPTIMIZERS["sm"].settings.model_validate({"x_scale": "auto"}, strict=True)


def test_hybrid_counts_the_jacobians_of_its_polishing_runs():
    r = run_optimizer("hybrid", lab_problem(), 0, Budget(max_evaluations=2000),
                      **hybrid("screening", {"sampler": "sobol"}, 256, n_candidates=2))
    polished = [r.extra[f"candidate_{i}"] for i in (1, 2)]
    # each SM iteration of a polish differences one Jacobian (the lab frame has no exact one)
    assert r.n_jacobians >= sum(c["n_iterations"] for c in polished) > 0
