"""Executors for runs and for model evaluations: serial, local processes, Dask.

OpenSees holds one global domain per process, so concurrent OpenSees models need separate
processes: local process pools use one single-threaded process per worker, and Dask
clusters are started with ``threads_per_worker=1``.

- ``map_unordered(fn, items, backend, workers, scheduler)`` yields (index, result) as
  items finish: used by the study runner for whole runs.
- ``ProcessRunner`` / ``DaskRunner`` evaluate a population of parameter points of one run
  in parallel; pass one as ``UpdatingProblem(..., runner=...)``. Results come back in
  input order, so a run gives the same numbers with any runner.
"""

from __future__ import annotations

import concurrent.futures as cf
import logging
import multiprocessing as mp
from collections.abc import Callable, Iterator, Sequence

from framework.errors import ModelEvaluationError
from framework.models.base import modal_many

log = logging.getLogger(__name__)


def _context():
    # fork is fast and safe here: no OpenSees domain or thread pool is alive in the parent
    # when workers start; "spawn" is used where fork is unavailable.
    return mp.get_context("fork") if "fork" in mp.get_all_start_methods() else mp.get_context("spawn")


def dask_client(scheduler: str | None = None, workers: int = 2):
    """A distributed Client: connect to ``scheduler`` or start a local cluster of processes."""
    from distributed import Client, LocalCluster

    if scheduler:
        return Client(scheduler)
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
        with cf.ProcessPoolExecutor(max_workers=workers, mp_context=_context()) as pool:
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


def _chunks(seq: Sequence, n: int) -> list[list]:
    size = max(1, -(-len(seq) // n))
    return [list(seq[i : i + size]) for i in range(0, len(seq), size)]


class ProcessRunner:
    """Evaluate a population across a persistent local process pool (input order kept)."""

    def __init__(self, workers: int = 2):
        self.workers = workers
        self._pool: cf.ProcessPoolExecutor | None = None

    def __getstate__(self):
        return {"workers": self.workers, "_pool": None}

    def _ensure(self) -> cf.ProcessPoolExecutor:
        if self._pool is None:
            self._pool = cf.ProcessPoolExecutor(max_workers=self.workers, mp_context=_context())
        return self._pool

    def __call__(self, model, thetas: Sequence[dict]) -> list:
        chunks = _chunks(list(thetas), self.workers)
        try:
            parts = list(self._ensure().map(_evaluate_chunk, [(model, c) for c in chunks]))
        except cf.process.BrokenProcessPool:
            log.warning("evaluation worker died; restarting the pool and redoing the population")
            self.close()
            parts = list(self._ensure().map(_evaluate_chunk, [(model, c) for c in chunks]))
        return [r for part in parts for r in part]

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(cancel_futures=True)
            self._pool = None


class DaskRunner:
    """Evaluate a population on a Dask cluster (one task per chunk, input order kept).

    With ``client=None`` the runner must be called inside a Dask task: it uses
    ``worker_client()``, which secedes the task from the worker's thread pool while it
    waits, so a run executing on a worker can farm its population out to the same
    cluster without deadlock.
    """

    def __init__(self, client=None, chunks: int | None = None):
        self.client = client
        self.chunks = chunks

    def __getstate__(self):
        return {"client": None, "chunks": self.chunks}

    def _run(self, client, model, thetas):
        n = self.chunks or max(1, len(client.scheduler_info().get("workers", {})))
        futures = client.map(_evaluate_chunk, [(model, c) for c in _chunks(list(thetas), n)], pure=False)
        return [r for part in client.gather(futures) for r in part]

    def __call__(self, model, thetas: Sequence[dict]) -> list:
        if self.client is not None:
            return self._run(self.client, model, thetas)
        from distributed import worker_client

        with worker_client() as client:
            return self._run(client, model, thetas)
