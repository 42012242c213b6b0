"""Run kinds on one base (issue 24): typed Kind objects, one status vocabulary, one failure row,
one runner and isolation path, one preflight wrapping, one report check, the shape hook."""

import dataclasses
import os
import textwrap

import pandas as pd
import pytest

from framework.core.errors import InputError
from framework.core.status import FAILURES, Status, succeeded
from framework.study.config import validate
from framework.study.kinds import KINDS, base, get_kind
from framework.study.runner import run_study
from framework.study.schema import StudyHeader

LAB = {"structure": {"name": "lab_frame_3dof"}, "measured": {"builtin": "lab_frame", "case": "base"}}
QUIET = {"execution": {"progress": False}}

#: one tiny study of every kind (seconds each)
TINY = {
    "updating": {**LAB, "kind": "updating", "budget": {"max_evaluations": 40, "stall_iterations": 20}, "runs": 1,
                 "algorithms": {"sm": {"algorithm": "sm"}, "pso": {"algorithm": "pso", "settings": {"swarm_size": 8}}}},
    "analysis": {**LAB, "kind": "analysis", "points": {"initial": {}, "stiffer": {"ratios": {"kxx": 1.2}}}},
    "posterior": {**LAB, "kind": "posterior", "sampler": {"walkers": 16, "steps": 12, "burn": 2}, "map_starts": 1,
                  "predictive_draws": 0},
    "damage": {"kind": "damage", "procedures": ["single_objective"], "pso": {"evaluations": 40, "swarm_size": 10},
               "polish_evaluations": 20},
    "identification": {"kind": "identification", "tests": {"snap": {
        "structure": "lab_frame", "test": "snap_back", "seed": 4, "duration_s": 20.0, "methods": ["ssi_cov"],
        "subspace": {"orders": {"min": 6, "max": 40, "step": 2}, "block_rows": 20, "decimate": 4,
                     "band_hz": [0.5, 15.0]}}}},
    "diagnose": {"kind": "diagnose", "structure": "beam", "measured": {"generate": {"hidden": {}, "noise": "high"}},
                 "seed": 1, "settings": {"n_starts": 1, "max_evaluations": 60}},
}
#: the status of a run that finished with a usable result, where the kind has no finer reason
OK_KINDS = ("analysis", "posterior", "damage", "identification", "diagnose")


def _config(tmp_path, kind: str, **changes) -> StudyHeader:
    return validate({"study": f"tiny_{kind}", "output": str(tmp_path / kind), **QUIET, **TINY[kind], **changes})


def test_every_kind_is_a_typed_object_on_one_base():
    assert set(TINY) == set(KINDS)
    for name, kind in KINDS.items():
        assert isinstance(kind, base.Kind) and kind.name == name and get_kind(name) is kind
        assert issubclass(kind.config, StudyHeader) and kind.tables and callable(kind.run)
        assert kind.report in (base.ANALYSES, None) or isinstance(kind.report, type)
    # the kinds that evaluate a structure's model through the run's runner, and those with mode shapes
    assert {n for n, k in KINDS.items() if k.evaluates_model} == {"updating", "analysis", "posterior"}
    assert {n for n, k in KINDS.items() if k.shapes is not None} == {"updating", "analysis", "damage"}
    with pytest.raises(InputError, match=r"kind: unknown run kind 'nope'; known: \['analysis', 'damage'"):
        get_kind("nope")


def test_every_kind_writes_statuses_of_the_one_vocabulary(tmp_path):
    """Every row with a status, of every table of a tiny study of each kind, has a status of
    :class:`Status`; a kind without a finer reason says ``ok``, an updating run its optimizer's
    stop reason. (tests/conftest.py checks the rows of every study of the test suite too.)"""
    for name, kind in KINDS.items():
        tables = run_study(_config(tmp_path, name), figures=False)
        first = tables[kind.tables[0]]
        assert len(first) >= 1 and set(first["status"]) <= set(Status), (name, set(first["status"]))
        assert first["status"].map(succeeded).all(), (name, first[["status", "error"]])
        assert (first["error"].fillna("") == "").all(), name
        if name in OK_KINDS:
            assert set(first["status"]) == {Status.OK}, name
        for table, df in tables.items():
            if "status" in df:
                assert set(df["status"]) <= set(Status), (name, table)
    runs = pd.read_csv(tmp_path / "updating" / "runs.csv")
    assert set(runs["status"]) <= {Status.TARGET, Status.STALLED, Status.CONVERGED, Status.BUDGET}


def test_a_run_that_raises_is_one_failure_row_of_its_kind(tmp_path, monkeypatch):
    """The engine's failure row is the same for every kind: the first table's one row, status
    ``error``, the exception as ``"<type>: <message>"``, the traceback, every other table empty."""

    def raising(spec, runner=None):
        raise ZeroDivisionError("no run today")

    for name in ("updating", "identification", "damage"):
        monkeypatch.setitem(KINDS, name, dataclasses.replace(KINDS[name], run=raising))
        tables = run_study(_config(tmp_path, name), figures=False)
        first = tables[KINDS[name].tables[0]]
        assert first["status"].tolist() == [Status.ERROR] * len(first)
        assert set(first["error"]) == {"ZeroDivisionError: no run today"}
        assert first["traceback"].str.contains("ZeroDivisionError").all()
        assert all(df.empty for t, df in tables.items() if t != KINDS[name].tables[0])
    assert base.failure(ValueError("bad")) == {"status": Status.FAILED, "error": "ValueError: bad"}
    assert base.failure("no mode identified") == {"status": "failed", "error": "no mode identified"}
    assert FAILURES == {"failed", "error"} and succeeded("completed") and not succeeded("error")


def test_preflight_errors_are_wrapped_in_one_place():
    """Whatever a kind's preflight raises for bad input, the study gets one InputError naming the
    study; specs with the same preflight key are checked once."""
    checked = []

    def check(spec, build_references):
        checked.append(spec["label"])
        if spec["label"] == "b":
            raise KeyError("kxx")

    kind = dataclasses.replace(KINDS["updating"], preflight=check, preflight_key=lambda spec: spec["task"]["k"])
    specs = [{"study": "s", "label": label, "task": {"k": k}} for label, k in (("a", 1), ("a2", 1), ("b", 2))]
    with pytest.raises(InputError, match=r"^study 's': KeyError: 'kxx'$"):
        base.preflight(kind, specs)
    assert checked == ["a", "b"]


@pytest.mark.parametrize("kind, report, message", [
    ("updating", {"nonsense": {}}, r"report\.nonsense: unknown analysis; known: \["),
    ("damage", {"damage_summary": {"treshold": 0.1}}, r"report\.damage_summary: .*treshold"),
    ("identification", {"figures": 3}, r"report\.figures: unknown key; known: \['export'\] \(value: 3\)"),
    ("diagnose", {"outcomes": "yes"}, r"report\.outcomes: Input should be a valid boolean \(value: 'yes'\)"),
    ("posterior", {"coverage": {}}, r"report: kind 'posterior' has no report options, got \['coverage'\]"),
])
def test_report_options_are_checked_in_one_place(tmp_path, kind, report, message):
    with pytest.raises(InputError, match=rf"^tiny.yaml: {message}"):
        validate({"study": "t", **TINY[kind], "report": report}, source="tiny.yaml")


# ---- one runner and isolation path -----------------------------------------------------------------------------
USER_MODEL = '''
    """A user's model (module:function) that records the process of every evaluation."""
    import os

    from framework.structures.lab_frame.model import ThreeDofFrame

    LOG = os.path.join(os.path.dirname(__file__), "pids.txt")


    class PidFrame:
        """The 3-DOF lab frame, evaluated one point at a time (not vectorized)."""

        def __init__(self, **options):
            self.frame = ThreeDofFrame(**options)

        @property
        def parameters(self):
            return self.frame.parameters

        @property
        def dofs(self):
            return self.frame.dofs

        def modal(self, theta):
            with open(LOG, "a") as f:
                f.write(f"{os.getpid()}\\n")
            return self.frame.modal(theta)


    def make(**options):
        return PidFrame(**options)
'''


def _evaluation_pids(tmp_path, kind: str, **changes) -> set[int]:
    log = tmp_path / "pids.txt"
    log.unlink(missing_ok=True)
    cfg = _config(tmp_path, kind, structure={"name": "pid_model:make"}, **changes)
    tables = run_study(cfg, figures=False)
    assert tables[KINDS[kind].tables[0]]["status"].map(succeeded).all()
    return {int(line) for line in log.read_text().split()}


def test_a_user_model_is_isolated_the_same_way_in_updating_posterior_and_analysis_runs(tmp_path, monkeypatch):
    """``isolate: auto``: the evaluations of a user's model (``module:function``) run in an isolated
    worker process in every kind that evaluates a model through the engine (the posterior kind
    used to evaluate it in the run's own process); ``isolate: false`` keeps them in process."""
    (tmp_path / "pid_model.py").write_text(textwrap.dedent(USER_MODEL))
    monkeypatch.syspath_prepend(str(tmp_path))
    here = os.getpid()
    for kind in ("updating", "posterior", "analysis"):
        pids = _evaluation_pids(tmp_path, kind)
        assert pids and here not in pids, kind  # every evaluation in an isolated worker
        pids = _evaluation_pids(tmp_path, kind, execution={"progress": False, "isolate": False})
        assert pids == {here}, kind
