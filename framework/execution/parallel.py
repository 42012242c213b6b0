"""Executors for runs and for model evaluations: serial, local processes, Dask.

OpenSees holds one global domain per process, so concurrent OpenSees models need separate
processes: local process pools use one single-threaded process per worker, and Dask
clusters are started with ``threads_per_worker=1``.

- ``map_unordered(fn, items, backend, workers, scheduler)`` yields (index, result) as
  items finish: used by the study runner for whole runs.
- ``ProcessRunner`` / ``DaskRunner`` evaluate a population of parameter points of one run
  in parallel; pass one as ``run_optimizer(..., runner=...)`` or ``problem.evaluate(X, runner)``. Results come back in
  input order, so a run gives the same numbers with any runner.
- ``make_evaluation_runner(backend, workers, isolate, timeout_s, ...)`` picks the runner of a
  run's evaluations and returns (runner, close).

A crash, ``os._exit`` or hang of a user's model is contained by evaluating in isolated
workers (:mod:`framework.execution.isolation`): ProcessRunner always does, the serial and Dask runners
do with ``isolate=True`` or a timeout. Every worker process started here ends when its
parent dies (:func:`framework.execution.isolation.guard_parent_death`), so killing a study leaves no
orphan behind.
"""

from __future__ import annotations

import concurrent.futures as cf
import logging
import multiprocessing as mp
import os
import threading
from collections.abc import Callable, Iterator, Sequence

from framework.core.errors import InputError, ModelEvaluationError
from framework.execution.isolation import IsolatedRunner, guard_parent_death
from framework.models.base import modal_many

log = logging.getLogger(__name__)


def _context():
    # fork is fast and safe here: no OpenSees domain or thread pool is alive in the parent
    # when workers start; "spawn" is used where fork is unavailable.
    return mp.get_context("fork") if "fork" in mp.get_all_start_methods() else mp.get_context("spawn")


#: how long to try to reach a Dask scheduler before giving up (s)
CONNECT_TIMEOUT_S = 5.0


def dask_client(scheduler: str | None = None, workers: int = 2, timeout_s: float | None = None):
    """A distributed Client: connect to ``scheduler`` (InputError naming the address if it
    cannot be reached within ``timeout_s``, default :data:`CONNECT_TIMEOUT_S`) or start a
    local cluster of processes."""
    from distributed import Client, LocalCluster

    if scheduler:
        timeout_s = CONNECT_TIMEOUT_S if timeout_s is None else timeout_s
        try:
            return Client(scheduler, timeout=timeout_s)
        except Exception as exc:  # refused, timed out, bad address, not a scheduler answering
            detail = " ".join(str(exc).split())[:200] or type(exc).__name__
            raise InputError(f"execution.scheduler (or --scheduler) {scheduler}: cannot connect to a Dask "
                             f"scheduler there within {timeout_s:g} s ({type(exc).__name__}: {detail})") from None
    cluster = LocalCluster(
        n_workers=workers,
        threads_per_worker=1,
        processes=True,
        dashboard_address=None,
        silence_logs=logging.ERROR,
    )
    return Client(cluster)


def map_unordered(
    fn: Callable,
    items: Sequence,
    backend: str = "serial",
    workers: int = 2,
    scheduler: str | None = None,
    client=None,
) -> Iterator[tuple[int, object]]:
    """Apply fn to every item; yield (index, result or exception) as they complete."""
    if backend == "serial" or len(items) == 0:
        for i, item in enumerate(items):
            yield i, _call(fn, item)
        return
    if backend == "processes":
        yield from _map_processes(fn, items, workers)
        return
    if backend == "dask":
        from distributed import as_completed

        own = client is None
        client = client or dask_client(scheduler, workers)
        try:
            futures = {client.submit(_call, fn, item, pure=False): i for i, item in enumerate(items)}
            for fut in as_completed(futures):
                try:
                    yield futures[fut], fut.result()
                except Exception as exc:  # worker died or task failed
                    yield futures[fut], exc
        finally:
            if own:
                cluster = getattr(client, "cluster", None)
                client.close()
                if cluster is not None:
                    cluster.close()
        return
    raise ValueError(f"unknown backend {backend!r}; use serial, processes or dask")


def _call(fn, item):
    try:
        return fn(item)
    except Exception as exc:  # returned, not raised: the caller records it
        return exc


def _map_processes(fn, items, workers) -> Iterator[tuple[int, object]]:
    """Process pool that survives a dead worker: the broken pool is replaced and the
    unfinished items are resubmitted (an item that kills workers twice is reported)."""
    pending = dict(enumerate(items))
    deaths: dict[int, int] = {}
    while pending:
        with cf.ProcessPoolExecutor(max_workers=workers, mp_context=_context(), initializer=guard_parent_death,
                                    initargs=(os.getpid(),)) as pool:
            futures = {pool.submit(_call, fn, item): i for i, item in pending.items()}
            broken = False
            for fut in cf.as_completed(futures):
                i = futures[fut]
                try:
                    result = fut.result()
                except cf.process.BrokenProcessPool:
                    broken = True
                    continue
                pending.pop(i, None)
                yield i, result
            if broken:
                for i in list(pending):
                    deaths[i] = deaths.get(i, 0) + 1
                    if deaths[i] >= 2:
                        pending.pop(i)
                        yield (
                            i,
                            ModelEvaluationError("worker_died", "the worker process died twice on this item"),
                        )
                log.warning("a worker process died; restarting the pool for %d item(s)", len(pending))


def _evaluate_chunk(args):
    model, thetas = args
    return modal_many(model, thetas)


_local_runners: dict[tuple, IsolatedRunner] = {}
_local_lock = threading.Lock()


def _evaluate_chunk_isolated(args):
    """A chunk evaluated by this process's isolated worker (e.g. on a Dask worker: the crash of
    a build kills a child of the Dask worker, not the Dask worker)."""
    model, thetas, timeout_s, isolate_vectorized = args
    with _local_lock:
        key = (timeout_s, isolate_vectorized)
        if key not in _local_runners:
            _local_runners[key] = IsolatedRunner(1, timeout_s, isolate_vectorized=isolate_vectorized)
        return _local_runners[key](model, thetas)


def _chunks(seq: Sequence, n: int) -> list[list]:
    size = max(1, -(-len(seq) // n))
    return [list(seq[i : i + size]) for i in range(0, len(seq), size)]


class ProcessRunner(IsolatedRunner):
    """Evaluate a population across ``workers`` persistent local processes (input order kept).

    Every model, vectorized or not, is evaluated in the workers, so a crash, ``sys.exit`` or
    (with ``timeout_s``) a hang of one evaluation is a recorded failure of that point only
    ("worker_crashed", "model_exit", "timeout"); see :class:`framework.execution.isolation.IsolatedRunner`.
    """

    def __init__(self, workers: int = 2, timeout_s: float | None = None, **options):
        super().__init__(workers, timeout_s, **options)


class DaskRunner:
    """Evaluate a population on a Dask cluster (one task per chunk, input order kept).

    With ``client=None`` the runner must be called inside a Dask task: it uses
    ``worker_client()``, which secedes the task from the worker's thread pool while it
    waits, so a run executing on a worker can farm its population out to the same
    cluster without deadlock. With ``isolate=True`` or a ``timeout_s`` each Dask worker
    evaluates its chunks in an isolated child process (:class:`IsolatedRunner`), so a
    crashing or hanging build is a recorded failure instead of a dead Dask worker.
    """

    def __init__(self, client=None, chunks: int | None = None, isolate: bool = False, timeout_s: float | None = None,
                 isolate_vectorized: bool = False):
        self.client = client
        self.chunks = chunks
        self.isolate = isolate or timeout_s is not None
        self.timeout_s = timeout_s
        self.isolate_vectorized = isolate_vectorized

    def __getstate__(self):
        return {**self.__dict__, "client": None}

    def _run(self, client, model, thetas):
        n = self.chunks or max(1, len(client.scheduler_info().get("workers", {})))
        chunks = _chunks(list(thetas), n)
        if self.isolate:
            tasks = [(model, c, self.timeout_s, self.isolate_vectorized) for c in chunks]
            futures = client.map(_evaluate_chunk_isolated, tasks, pure=False)
        else:
            futures = client.map(_evaluate_chunk, [(model, c) for c in chunks], pure=False)
        return [r for part in client.gather(futures) for r in part]

    def __call__(self, model, thetas: Sequence[dict]) -> list:
        if self.client is not None:
            return self._run(self.client, model, thetas)
        from distributed import worker_client

        with worker_client() as client:
            return self._run(client, model, thetas)


def _no_op() -> None:
    return None


def make_evaluation_runner(
    backend: str = "serial",
    workers: int = 2,
    isolate: bool = False,
    timeout_s: float | None = None,
    scheduler: str | None = None,
    client=None,
    isolate_vectorized: bool = False,
) -> tuple[Callable, Callable[[], None]]:
    """The runner of a run's model evaluations and the function that releases it.

    backend "serial": in this process (``modal_many``), or with ``isolate=True`` or a
    ``timeout_s`` (s) in one isolated worker process. "processes": ``workers`` isolated local
    processes (always isolated). "dask": the cluster this run executes on (inside a Dask
    worker), else ``client`` or the scheduler at ``scheduler``; isolated on each Dask worker
    with ``isolate`` or ``timeout_s``. Vectorized models (``modal_batch``) stay in-process in
    the serial and Dask cases unless ``isolate_vectorized``.
    """
    if timeout_s is not None:
        isolate = True
    if backend == "serial":
        if not isolate:
            return modal_many, _no_op
        runner = IsolatedRunner(1, timeout_s, isolate_vectorized=isolate_vectorized)
        return runner, runner.close
    if backend == "processes":
        runner = ProcessRunner(workers, timeout_s)
        return runner, runner.close
    if backend != "dask":
        raise ValueError(f"unknown evaluation backend {backend!r}; use serial, processes or dask")
    options = dict(isolate=isolate, timeout_s=timeout_s, isolate_vectorized=isolate_vectorized)
    if client is not None:
        return DaskRunner(client, **options), _no_op
    from distributed import Client, get_worker

    try:
        get_worker()
        return DaskRunner(None, **options), _no_op  # inside a Dask worker: use its cluster
    except ValueError:
        pass
    if not scheduler:
        raise ValueError("evaluation backend dask needs a scheduler address outside a Dask worker")
    own = Client(scheduler)
    return DaskRunner(own, **options), own.close
