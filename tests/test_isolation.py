"""Isolation of user build functions (issue 14, defect 6): exceptions, sys.exit, segfaults, NaN
and hangs are recorded failures of one evaluation; workers never outlive their parent."""

import faulthandler
import os
import pickle
import signal
import subprocess
import sys
import textwrap
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import psutil
import pytest

from framework.core.errors import ModelEvaluationError
from framework.execution.isolation import IsolatedRunner, exit_description, split
from framework.execution.parallel import DaskRunner, ProcessRunner, make_evaluation_runner
from framework.models.base import ModalResult, modal_many, safe_modal
from framework.structures.lab_frame.model import ThreeDofFrame
from framework.updating.evaluator import Evaluator
from framework.updating.problem import UpdatingProblem

pytest.importorskip("openseespy.opensees")

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # "tests.faulty_build" is the name a study config uses
    sys.path.insert(0, str(ROOT))
from tests import faulty_build as fb  # noqa: E402

TIMEOUT_S = 1.5
#: One point per region, normal points between them (the order matters: faults in the middle of shares).
REGIONS = [None, "raise", None, "exit", "segfault", None, "nan", None, "hang", None]
POINTS = [fb.theta_in(r) for r in REGIONS]
EXPECTED = [None if r is None else fb.EXPECTED_REASON[r] for r in REGIONS]


@pytest.fixture(scope="module")
def model():
    return fb.make_model()


@pytest.fixture(scope="module")
def reference(model):
    """Normal points evaluated in this process (the values isolated workers must reproduce)."""
    return model.modal(fb.theta_in(None))


def _reasons(results):
    return [r.reason if isinstance(r, ModelEvaluationError) else None for r in results]


def _assert_faults_recorded(results, reference):
    assert len(results) == len(POINTS)
    assert _reasons(results) == EXPECTED
    for region, res in zip(REGIONS, results):
        if region is None:
            assert isinstance(res, ModalResult)
            np.testing.assert_array_equal(res.frequencies_hz, reference.frequencies_hz)
            np.testing.assert_array_equal(res.shapes, reference.shapes)


def _children() -> set[int]:
    """Live (non-zombie) descendants of this process."""
    return {p.pid for p in psutil.Process().children(recursive=True) if _running(p)}


# ---- in-process: what can be caught without isolation ----------------------------------------
@dataclass(frozen=True)
class ExitingFrame(ThreeDofFrame):
    code: object = 3
    modal_batch = None

    def modal(self, theta):
        sys.exit(self.code)


@dataclass(frozen=True)
class InterruptedFrame(ThreeDofFrame):
    modal_batch = None

    def modal(self, theta):
        raise KeyboardInterrupt


def test_sys_exit_in_a_model_is_a_recorded_failure_not_the_end_of_the_process():
    res = safe_modal(ExitingFrame(code="bye"), {})
    assert isinstance(res, ModelEvaluationError) and res.reason == "model_exit"
    assert "sys.exit('bye')" in str(res)
    assert _reasons(modal_many(ExitingFrame(), [{}, {}])) == ["model_exit", "model_exit"]


def test_ctrl_c_still_stops_an_evaluation():
    with pytest.raises(KeyboardInterrupt):
        safe_modal(InterruptedFrame(), {})


def test_exit_and_nan_of_an_opensees_build_are_caught_in_process(model):
    res = safe_modal(model, fb.theta_in("exit"))
    assert res.reason == "model_exit" and "sys.exit(3)" in res.detail
    res = safe_modal(model, fb.theta_in("nan"))
    assert res.reason == "non_finite_input" and "uniaxialMaterial" in res.detail and "nan" in res.detail
    assert safe_modal(model, fb.theta_in("raise")).reason == "build_failed"
    assert isinstance(safe_modal(model, fb.theta_in(None)), ModalResult)  # the process is fine afterwards
    import openseespy.opensees as ops

    assert type(ops.node).__name__ == "builtin_function_or_method"  # the NaN guard is removed after a build


def test_undetermined_eigenvalues_are_a_failure():
    from framework.models.opensees import UNDETERMINED_EIGENVALUE, eigen

    class FakeOps:
        @staticmethod
        def eigen(*args):
            return [1.0, UNDETERMINED_EIGENVALUE]

    with pytest.raises(ModelEvaluationError, match="eigen_failed: non-finite or undetermined"):
        eigen(FakeOps, 2, "-fullGenLapack")


def test_faulty_build_regions_leave_the_measured_minimum_normal():
    assert fb.fault_region(fb.TRUTH) is None and fb.fault_region(fb.PARAMETERS.as_dict(fb.PARAMETERS.to_physical(
        fb.PARAMETERS.x_initial))) is None
    u = np.random.default_rng(0).random((4000, 2))
    regions = [fb.fault_region(dict(zip(fb.PARAMETERS.names, fb.PARAMETERS.to_physical(x)))) for x in u]
    shares = {r: regions.count(r) / len(u) for r in set(regions)}
    assert shares[None] > 0.85 and 0.001 < shares["hang"] < 0.005  # faults are rare, a hang rarer
    assert set(shares) == {None, *fb.EXPECTED_REASON}


# ---- isolated runners: every fault kind is a failure of its point only ------------------------
RUNNERS = {
    "isolated_1": lambda: IsolatedRunner(1, TIMEOUT_S),
    "processes_2": lambda: ProcessRunner(2, timeout_s=TIMEOUT_S),
    "factory_serial": lambda: make_evaluation_runner("serial", isolate=True, timeout_s=TIMEOUT_S),
    "factory_processes": lambda: make_evaluation_runner("processes", workers=3, timeout_s=TIMEOUT_S),
}


@pytest.mark.parametrize("kind", list(RUNNERS))
def test_each_fault_is_a_recorded_failure_of_its_point(kind, model, reference):
    before = _children()
    made = RUNNERS[kind]()
    runner, close = made if isinstance(made, tuple) else (made, made.close)
    try:
        results = runner(model, POINTS)
        _assert_faults_recorded(results, reference)
        crashed = results[REGIONS.index("segfault")]
        assert crashed.detail == "evaluation worker killed by signal 11 (SIGSEGV)"
        assert results[REGIONS.index("hang")].detail == f"no result after {TIMEOUT_S:g} s; worker stopped"
        again = runner(model, POINTS)  # the same runner, again: identical results
        assert _reasons(again) == _reasons(results)
        for a, b in zip(results, again):
            if isinstance(a, ModalResult):
                np.testing.assert_array_equal(a.frequencies_hz, b.frequencies_hz)
    finally:
        close()
    assert _children() <= before  # every worker stopped and reaped


def _evaluate(model, measured, X, runner):
    """A run's evaluator over the problem, evaluating X with the runner: (evaluator, evaluations)."""
    evaluator = Evaluator(UpdatingProblem(model, measured), runner=runner)
    return evaluator, evaluator.evaluate(X)


def test_the_problem_records_each_fault_with_its_reason(model):
    X = fb.PARAMETERS.to_normalized(np.array([[p[n] for n in fb.PARAMETERS.names] for p in POINTS]))
    with ProcessRunner(2, timeout_s=TIMEOUT_S) as runner:
        evaluator, ev = _evaluate(model, fb.measured(), X, runner)
    assert ev.reasons == EXPECTED
    assert list(ev.ok) == [r is None for r in REGIONS]
    np.testing.assert_allclose(ev.objective[~ev.ok], evaluator.problem.spec.failure_penalty)
    assert np.all(ev.objective[ev.ok] < 1.0)
    assert {r: evaluator.failures[r] for r in fb.EXPECTED_REASON.values()} == dict.fromkeys(
        fb.EXPECTED_REASON.values(), 1)


def test_a_crashing_point_costs_one_retry_not_a_restart_per_point(model, reference):
    points = [fb.theta_in(None)] * 5 + [fb.theta_in("segfault")] + [fb.theta_in(None)] * 6
    with IsolatedRunner(1) as runner:
        results = runner(model, points)
        assert runner.stats == {"started": 3, "crashed": 2}  # first worker, retry of the point, the rest
        assert _reasons(results) == [None] * 5 + ["worker_crashed"] + [None] * 6
        runner(model, [fb.theta_in(None)] * 4)
        assert runner.stats["started"] == 3  # the worker persists across calls
        runner(model, [fb.theta_in("raise"), fb.theta_in(None)])
        assert runner.stats["retired"] == 1 and runner.stats["started"] == 4  # fresh worker after a failure


def test_a_transient_worker_death_is_retried_in_a_fresh_worker(tmp_path):
    sys.path.insert(0, str(ROOT / "tests"))
    import fault_models

    thetas = [{"kxx": 20000.0 + 100 * i} for i in range(5)]
    with IsolatedRunner(1) as runner:
        results = runner(fault_models.make_dying(str(tmp_path / "m")), thetas)
        assert runner.stats["crashed"] == 1
    ref = modal_many(ThreeDofFrame(), thetas)
    for a, b in zip(results, ref):
        np.testing.assert_array_equal(a.frequencies_hz, b.frequencies_hz)


def test_nan_that_reaches_opensees_is_contained(reference):
    """Given a NaN, OpenSees reports undetermined eigenvalues or aborts (heap corruption, depending
    on the process's history): either way a failure of that point, and later points are right."""
    raw = fb.make_model(nan_reaches_opensees=True)
    points = [fb.theta_in(None), fb.theta_in("nan"), fb.theta_in(None), fb.theta_in("nan"), fb.theta_in(None)]
    with IsolatedRunner(1) as runner:
        results = runner(raw, points)
    assert _reasons(results)[0::2] == [None] * 3
    assert set(_reasons(results)[1::2]) <= {"eigen_failed", "worker_crashed"}
    for res in results[0::2]:
        np.testing.assert_array_equal(res.frequencies_hz, reference.frequencies_hz)


def test_a_worker_killed_while_idle_is_replaced_without_a_failure(model):
    before = _children()
    with IsolatedRunner(1) as runner:
        runner(model, [fb.theta_in(None)])
        (pid,) = _children() - before
        os.kill(pid, signal.SIGKILL)
        time.sleep(0.2)
        assert _reasons(runner(model, [fb.theta_in(None)] * 3)) == [None] * 3
        assert runner.stats["started"] == 2 and pid not in _children()


_inherited: list = []


def _use_inherited_runner():
    (runner,) = _inherited  # a copy made by fork, holding the parent's worker
    runner.close()
    results = runner(fb.make_model(), [fb.theta_in(None)])  # starts a worker of its own
    runner.close()
    return _reasons(results)


def test_a_runner_inherited_by_a_forked_process_leaves_the_parents_workers_alone(model):
    import concurrent.futures as cf
    import multiprocessing as mp

    with IsolatedRunner(1) as runner:
        runner(model, [fb.theta_in(None)])
        _inherited[:] = [runner]
        try:
            with cf.ProcessPoolExecutor(1, mp_context=mp.get_context("fork")) as pool:
                assert pool.submit(_use_inherited_runner).result() == [None]
        finally:
            _inherited.clear()
        time.sleep(0.2)
        runner(model, [fb.theta_in(None)] * 2)
        assert runner.stats == {"started": 1}  # the parent's worker was neither stopped nor replaced


def test_a_timed_out_worker_is_killed_and_reaped(model):
    before = _children()
    with IsolatedRunner(1, timeout_s=0.5, grace_s=0.2) as runner:
        runner(model, [fb.theta_in(None)])
        (pid,) = _children() - before
        results = runner(model, [fb.theta_in("hang"), fb.theta_in(None)])
        assert _reasons(results) == ["timeout", None]
        with pytest.raises(ChildProcessError):  # reaped: no zombie left
            os.waitpid(pid, os.WNOHANG)
        assert runner.stats == {"started": 2, "timed_out": 1}


@dataclass(frozen=True)
class CrashingBatchFrame(ThreeDofFrame):
    """A vectorized model whose batch kills the process when it holds a point with kxx > limit."""

    limit: float = 23000.0

    def modal_batch(self, thetas):
        if any(t.get("kxx", 0.0) > self.limit for t in thetas):
            faulthandler.disable()
            os.kill(os.getpid(), signal.SIGSEGV)
        return [safe_modal(self, t) for t in thetas]

    def modal(self, theta):
        if theta.get("kxx", 0.0) > self.limit:
            faulthandler.disable()
            os.kill(os.getpid(), signal.SIGSEGV)
        return super().modal(theta)


def test_vectorized_models_stay_in_process_unless_isolation_is_forced():
    thetas = [{"kxx": 20000.0 + 500 * i} for i in range(8)]
    ref = modal_many(ThreeDofFrame(), thetas)
    runner, close = make_evaluation_runner("serial", isolate=True)
    try:
        runner(ThreeDofFrame(), thetas)
        assert runner.stats["started"] == 0
    finally:
        close()
    runner, close = make_evaluation_runner("serial", isolate=True, isolate_vectorized=True)
    try:
        results = runner(CrashingBatchFrame(), thetas)  # kxx = 23500 (the last point) crashes
        assert runner.stats["crashed"] == 1 + 2  # the batch, then the crashing point twice
    finally:
        close()
    assert _reasons(results) == [None] * 7 + ["worker_crashed"]
    for a, b in zip(results[:7], ref[:7]):
        np.testing.assert_array_equal(a.frequencies_hz, b.frequencies_hz)


def test_a_model_the_worker_cannot_load_fails_the_call_and_the_runner_recovers(model):
    with IsolatedRunner(1) as runner:
        before = _children()
        with pytest.raises(RuntimeError, match="the worker cannot load the model: ValueError: not here"):
            runner(UnloadableModel(), [{}])
        assert _children() <= before
        assert _reasons(runner(model, [fb.theta_in(None)])) == [None]
    with pytest.raises(TypeError, match="cannot be sent to an isolated worker"):
        IsolatedRunner(1)(LocalModel(), [{}])


class UnloadableModel:
    modal_batch = None

    def __reduce__(self):
        return (_refuse, ())


def _refuse():  # called when a worker unpickles the model
    raise ValueError("not here")


class LocalModel(ThreeDofFrame):
    def __reduce__(self):
        raise pickle.PicklingError("local build function")


def test_runner_configuration_and_helpers():
    assert make_evaluation_runner("serial")[0] is modal_many
    runner, close = make_evaluation_runner("processes", workers=3)
    assert isinstance(runner, ProcessRunner) and runner.workers == 3
    assert pickle.loads(pickle.dumps(runner)).workers == 3
    close()
    with pytest.raises(ValueError, match="unknown evaluation backend 'threads'"):
        make_evaluation_runner("threads")
    with pytest.raises(ValueError, match="timeout_s must be a finite number > 0"):
        IsolatedRunner(1, timeout_s=0)
    with pytest.raises(ValueError, match="workers must be an integer >= 1"):
        IsolatedRunner(True)
    assert [list(r) for r in split(7, 3)] == [[0, 1, 2], [3, 4], [5, 6]]
    assert exit_description(-11) == "killed by signal 11 (SIGSEGV)"
    assert exit_description(3) == "exited with code 3"
    assert IsolatedRunner(2)(ThreeDofFrame(), []) == []


def test_without_fork_workers_are_spawned(monkeypatch, model, reference):
    monkeypatch.delattr(os, "fork")  # as on a platform without fork
    with IsolatedRunner(1, timeout_s=30.0) as runner:
        results = runner(model, [fb.theta_in(None), fb.theta_in("segfault"), fb.theta_in(None)])
        assert _reasons(results) == [None, "worker_crashed", None]
        assert runner.stats == {"started": 3, "crashed": 2}
    np.testing.assert_array_equal(results[2].frequencies_hz, reference.frequencies_hz)


def _reasons_in_a_run_worker(evaluation_backend):
    runner, close = make_evaluation_runner(evaluation_backend, workers=2, timeout_s=TIMEOUT_S)
    try:
        return _reasons(runner(fb.make_model(), POINTS))
    finally:
        close()


def test_runs_on_the_process_backend_use_isolated_workers():
    from framework.execution.parallel import map_unordered

    done = dict(map_unordered(_reasons_in_a_run_worker, ["serial", "processes"], backend="processes", workers=2))
    assert done == {0: EXPECTED, 1: EXPECTED}


# ---- Dask: on a Dask worker, isolation uses a child process of the worker ---------------------
def test_dask_workers_survive_faulty_builds(model, reference):
    pytest.importorskip("distributed")
    from framework.execution.parallel import dask_client

    client = dask_client(workers=1)
    try:
        before = set(client.scheduler_info()["workers"])
        runner = DaskRunner(client, chunks=2, timeout_s=TIMEOUT_S)
        _assert_faults_recorded(runner(model, POINTS), reference)
        # a run executing on a Dask worker (a daemonic process) uses its own isolated worker
        fut = client.submit(_run_on_worker, model, POINTS, pure=False)
        _assert_faults_recorded(fut.result(timeout=120), reference)
        assert set(client.scheduler_info()["workers"]) == before  # no Dask worker died
    finally:
        client.close()
        client.cluster.close()


def _run_on_worker(model, points):
    runner, close = make_evaluation_runner("serial", timeout_s=TIMEOUT_S)
    try:
        return runner(model, points)
    finally:
        close()


# ---- orphans: workers end when their parent is killed -----------------------------------------
PARENT = textwrap.dedent("""
    import sys, threading, time
    sys.path.insert(0, {root!r})
    from tests import faulty_build as fb
    from framework.execution.parallel import ProcessRunner, map_unordered

    model = fb.make_model()

    def hang_in_isolated_worker(_):
        from framework.execution.isolation import IsolatedRunner
        return IsolatedRunner(1)(model, [fb.theta_in("hang")])

    runner = ProcessRunner(2)
    threading.Thread(target=runner, args=(model, [fb.theta_in("hang")] * 2), daemon=True).start()
    print("started", flush=True)
    list(map_unordered(hang_in_isolated_worker, [0, 1], backend="processes", workers=2))
""")


def test_workers_exit_when_the_study_process_is_killed():
    proc = subprocess.Popen([sys.executable, "-c", PARENT.format(root=str(ROOT))], cwd=ROOT, stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL, text=True, start_new_session=True)
    try:
        assert proc.stdout.readline().strip() == "started"
        parent = psutil.Process(proc.pid)
        descendants = []
        for _ in range(300):  # 2 evaluation workers + 2 run workers, each with 1 isolated worker
            descendants = parent.children(recursive=True)
            if len(descendants) >= 6:
                break
            time.sleep(0.1)
        assert len(descendants) >= 6, descendants
        time.sleep(0.5)  # every worker inside its hanging evaluation
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        alive = descendants
        for _ in range(100):
            alive = [p for p in alive if _running(p)]
            if not alive:
                break
            time.sleep(0.1)
        assert not alive, f"orphaned workers: {alive}"
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
        for p in psutil.Process(proc.pid).children(recursive=True) if psutil.pid_exists(proc.pid) else []:
            p.kill()


def _running(p: psutil.Process) -> bool:
    try:
        return p.status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False
