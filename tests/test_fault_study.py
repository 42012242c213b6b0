"""The fault study: a build function that raises, exits, segfaults, passes NaN or hangs never
stops a study; each fault is a failure counted by reason; tables agree across backends."""

from pathlib import Path

import pandas as pd
import pytest

from framework.study.config import load
from framework.study.runner import failure_counts, run_study

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "studies" / "fault_study.yaml"
TIMING = ["wall_s"]


def _run(tmp_path, name, overrides=()):
    cfg = load(CONFIG, [f"output={tmp_path / name}", "runs=1", "budget.max_evaluations=120",
                        "execution.progress=false", *overrides])
    return run_study(cfg, figures=False)


@pytest.fixture(scope="module")
def serial(tmp_path_factory, monkeypatch_module):
    return _run(tmp_path_factory.mktemp("fault"), "serial")


@pytest.fixture(scope="module")
def monkeypatch_module():
    mp = pytest.MonkeyPatch()
    mp.syspath_prepend(str(ROOT))
    yield mp
    mp.undo()


def test_every_fault_kind_is_counted_and_no_run_is_lost(serial):
    runs = serial["runs"]
    assert len(runs) == 3 and not (runs["status"] == "error").any(), runs[["label", "status", "error"]]
    counts = failure_counts(runs)  # failures.csv
    reasons = set(counts["reason"])
    assert {"build_failed", "model_exit", "worker_crashed", "non_finite_input", "timeout"} <= reasons, counts
    assert counts["n_failed"].sum() == runs["n_failed_evaluations"].sum()
    best = serial["parameters"].pivot_table(index="label", columns="parameter", values="value")
    assert (best["k1_n_per_m"] < 3.5e6).all()  # never a failed corner reported as updated value


@pytest.mark.parametrize("backend", ["processes", "dask"])
def test_fault_study_tables_identical_across_backends(serial, tmp_path, backend):
    other = _run(tmp_path, backend, [f"execution.backend={backend}", "execution.workers=2"])
    for name in ("runs", "parameters", "history"):
        a = serial[name].drop(columns=[c for c in TIMING if c in serial[name]])
        b = other[name].drop(columns=[c for c in TIMING if c in other[name]])
        pd.testing.assert_frame_equal(a, b, check_exact=True)
