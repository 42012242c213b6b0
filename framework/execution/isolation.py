"""Isolated model evaluation: a user's build function cannot stop, crash or hang a study.

:class:`IsolatedRunner` is a runner (``runner(model, thetas) -> list`` of ModalResult or
ModelEvaluationError, input order kept) that evaluates in persistent worker processes forked
from the caller. Each worker gets a contiguous share of the points and sends back one result
per point, so the parent always knows which point a worker was evaluating when it

- died (segfault, abort, ``os._exit``): the point is retried once, as the first point of a
  fresh worker (a transient death, or one caused by an earlier point's leftovers, is not the
  point's fault); a second death records ``ModelEvaluationError("worker_crashed",
  "evaluation worker killed by signal 11 (SIGSEGV)")``;
- gave no result within ``timeout_s``: the worker is stopped (SIGTERM, SIGKILL after
  ``grace_s``) and reaped, the point is recorded as ``"timeout"`` (not retried);

and the rest of that share goes on in a new worker. A population of n points with one
crashing point costs n + 1 evaluations and two extra worker starts, not n restarts. After any
failed evaluation the worker is replaced too (``fresh_after_failure``): a failure inside
native code can leave the process corrupted (OpenSees' full LAPACK eigen solver given a NaN
stiffness reports undetermined eigenvalues and leaves a damaged heap that aborts a later,
valid evaluation), so every point is evaluated in a process where nothing has failed yet.
Workers start on the first call and are forked from the caller (a copy of it at that moment:
imported libraries come for free, a start costs a few milliseconds). Vectorized models
(``modal_batch``) are evaluated a share at a time; if such a share kills its worker it is
redone point by point to find the culprit.

Workers end when their parent dies (:func:`guard_parent_death`): the Linux-only
``prctl(PR_SET_PDEATHSIG, SIGKILL)`` plus a portable watchdog thread polling ``os.getppid()``.

Why hand-written rather than ``concurrent.futures`` or ``multiprocessing.Pool``: a pool cannot
tell which task killed a worker (the whole pool breaks with every pending task), has no
per-task timeout that stops the task, and ``multiprocessing`` refuses to start children from
daemonic processes such as Dask workers. Workers are started with ``os.fork()``; where fork
does not exist, with the ``spawn`` method of multiprocessing (models must then be importable).
"""

from __future__ import annotations

import contextlib
import ctypes
import logging
import math
import multiprocessing as mp
import os
import pickle
import signal
import sys
import threading
import time
import traceback
import warnings
import weakref
from collections import Counter, deque
from collections.abc import Mapping, Sequence
from multiprocessing.connection import Connection, wait

from framework.core.errors import ModelEvaluationError
from framework.models.base import ModalResult, modal_many, safe_modal

log = logging.getLogger(__name__)

#: ``PR_SET_PDEATHSIG`` of <linux/prctl.h>.
_PR_SET_PDEATHSIG = 1
#: Longest sleep of a waiting parent between checks that its busy workers are alive (s).
POLL_S = 0.2
#: Exit code of a worker whose own loop failed (not the model: that is reported per point).
_WORKER_BUG_EXIT = 70


# ---- parent-death guard ---------------------------------------------------------------------
def guard_parent_death(parent_pid: int, interval_s: float = 0.5) -> None:
    """End this worker process as soon as its parent process ``parent_pid`` dies.

    Linux: the kernel sends SIGKILL when the parent dies (``prctl(PR_SET_PDEATHSIG)``; the
    kernel's "parent" is the thread that forked this process, so a worker forked by a thread
    that ends before its process is killed early: callers replace a worker found dead while
    idle). Everywhere: a daemon thread checks every ``interval_s`` whether ``os.getppid()``
    changed (an orphan is re-parented) and calls ``os._exit``; unlike the signal it cannot
    act while native code holds the GIL. Call it first thing in a worker (e.g. as the
    ``initializer`` of a process pool with ``initargs=(os.getpid(),)``).
    """
    if sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):
            ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
    if os.getppid() != parent_pid:  # the parent died before the guard was in place
        os._exit(1)
    watcher = threading.Thread(target=_watch_parent, args=(parent_pid, interval_s), name="gomu-parent-watch",
                               daemon=True)
    watcher.start()


def _watch_parent(parent_pid: int, interval_s: float) -> None:
    while True:
        time.sleep(interval_s)
        if os.getppid() != parent_pid:
            os._exit(1)


def exit_description(exitcode: int | None) -> str:
    """'killed by signal 11 (SIGSEGV)' or 'exited with code 3' from a process exit code."""
    if exitcode is None:
        return "ended (exit status unknown)"
    if exitcode < 0:
        try:
            name = signal.Signals(-exitcode).name
        except ValueError:
            name = "unknown signal"
        return f"killed by signal {-exitcode} ({name})"
    return f"exited with code {exitcode}"


# ---- the worker process ---------------------------------------------------------------------
def _encode(result) -> bytes:
    """Pickle one result; an unpicklable one becomes a failure of that point."""
    try:
        return pickle.dumps(result, protocol=pickle.HIGHEST_PROTOCOL)
    except Exception as exc:
        error = ModelEvaluationError("result_not_picklable", f"{type(exc).__name__}: {exc}")
        return pickle.dumps(error, protocol=pickle.HIGHEST_PROTOCOL)


def _decode(payload: bytes):
    try:
        return pickle.loads(payload)
    except Exception as exc:
        return ModelEvaluationError("result_not_picklable", f"{type(exc).__name__}: {exc}")


def _evaluate_share(model, thetas: list[dict]) -> list:
    """modal_batch on a whole share; a batch that raises is redone point by point."""
    try:
        results = list(model.modal_batch(thetas))
        if len(results) == len(thetas):
            return results
    except (Exception, SystemExit):
        pass
    return [safe_modal(model, theta) for theta in thetas]


def _serve(conn: Connection, parent_pid: int) -> None:
    """Worker loop. Receives ("run", model pickle or None, [(index, theta)], batch, fresh) and
    answers ("done", index, result) per point or ("batch", [(index, result)]); after a failed
    point with ``fresh`` it sends ("retire",) and ends. ("stop",) or a closed pipe ends it."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is for the parent, which stops the workers
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    guard_parent_death(parent_pid)
    model = None
    while True:
        try:
            message = conn.recv()
        except (EOFError, OSError):
            return
        if message[0] == "stop":
            return
        _, blob, items, batch, fresh = message
        if blob is not None:
            try:
                model = pickle.loads(blob)
            except Exception as exc:
                conn.send(("fatal", f"the worker cannot load the model: {type(exc).__name__}: {exc}"))
                return
        if batch:
            results = _evaluate_share(model, [theta for _, theta in items])
            conn.send(("batch", [(i, _encode(r)) for (i, _), r in zip(items, results)]))
            continue
        for i, theta in items:
            result = safe_modal(model, theta)
            conn.send(("done", i, _encode(result)))
            if fresh and not isinstance(result, ModalResult):
                conn.send(("retire",))
                return


def _run_child(child: Connection, parent_pid: int) -> None:
    """Body of a forked worker: never returns into the caller's stack."""
    code = 0
    try:
        _serve(child, parent_pid)
    except (BrokenPipeError, ConnectionResetError):  # the parent stopped listening: nothing to report
        pass
    except BaseException:
        code = _WORKER_BUG_EXIT
        with contextlib.suppress(Exception):
            traceback.print_exc()
            sys.stderr.flush()
    finally:
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(Exception):
                stream.flush()
        os._exit(code)


class _Worker:
    """One worker process and the parent's end of its pipe."""

    def __init__(self) -> None:
        parent_pid = self.owner = os.getpid()
        self.conn, child = mp.Pipe(duplex=True)
        self.model_blob: bytes | None = None
        self.exitcode: int | None = None
        self._ended = False
        self._process = None
        if hasattr(os, "fork"):
            for stream in (sys.stdout, sys.stderr):  # or the child may flush the parent's pending text again
                with contextlib.suppress(Exception):
                    stream.flush()
            with warnings.catch_warnings():
                # "multi-threaded, fork() may deadlock": the child runs only _serve and the model
                warnings.simplefilter("ignore", DeprecationWarning)
                pid = os.fork()
            if pid == 0:
                self.conn.close()
                _run_child(child, parent_pid)
            self.pid = pid
        else:  # platforms without fork
            self._process = mp.get_context("spawn").Process(target=_serve, args=(child, parent_pid), daemon=True)
            self._process.start()
            self.pid = self._process.pid
        child.close()

    def poll(self) -> bool:
        """True when the process has ended (it is then reaped and ``exitcode`` is set)."""
        if self._ended:
            return True
        if os.getpid() != self.owner:  # a copy inherited by a forked process: not its child
            self._ended = True
            return True
        if self._process is not None:  # platforms without fork
            if self._process.exitcode is not None:
                self._ended, self.exitcode = True, self._process.exitcode
            return self._ended
        try:
            pid, status = os.waitpid(self.pid, os.WNOHANG)
        except ChildProcessError:  # reaped by someone else
            self._ended = True
            return True
        if pid:
            self._ended, self.exitcode = True, os.waitstatus_to_exitcode(status)
        return self._ended

    def _signal(self, hard: bool) -> None:
        """SIGTERM (or SIGKILL if ``hard``) to a process that has not ended."""
        if self.poll():
            return
        if self._process is not None:  # platforms without fork
            if hard:
                self._process.kill()
            else:
                self._process.terminate()
            return
        with contextlib.suppress(ProcessLookupError):
            os.kill(self.pid, signal.SIGKILL if hard else signal.SIGTERM)

    def ask_to_stop(self) -> None:
        if os.getpid() == self.owner:
            with contextlib.suppress(OSError, ValueError):
                self.conn.send(("stop",))

    def reap(self, until: float) -> None:
        """Wait until the monotonic time ``until`` for the process to end, then SIGKILL and reap it."""
        while not self.poll() and time.monotonic() < until:
            time.sleep(0.005)
        if not self.poll():
            self._signal(hard=True)
            while not self.poll():
                time.sleep(0.005)
        self.conn.close()

    def kill(self, grace_s: float) -> None:
        """SIGTERM, then SIGKILL after ``grace_s``; reaped, no zombie left."""
        self._signal(hard=False)
        self.reap(time.monotonic() + grace_s)


def stop_workers(workers: list, grace_s: float) -> None:
    """Ask every worker to stop, SIGKILL those still running after ``grace_s``, reap all."""
    live = [w for w in workers if w is not None]
    for w in live:
        w.ask_to_stop()
    until = time.monotonic() + grace_s
    for w in live:
        w.reap(until)
    workers[:] = [None] * len(workers)


# ---- the runner -----------------------------------------------------------------------------
class _Share:
    """The points of one population given to one worker slot."""

    def __init__(self, slot: int, indices: range, batch: bool):
        self.slot = slot
        self.queue: deque[int] = deque(indices)
        self.in_flight: deque[int] = deque()
        self.batch = batch
        self.deadline: float | None = None

    def requeue(self, first: list[int]) -> None:
        """Put ``first`` and the unfinished points back at the front of the queue."""
        rest = first + list(self.in_flight)
        self.in_flight.clear()
        self.queue.extendleft(reversed(rest))
        self.deadline = None


def split(n: int, k: int) -> list[range]:
    """n indices in k contiguous shares whose sizes differ by at most one."""
    size, extra = divmod(n, k)
    bounds = [0]
    for j in range(k):
        bounds.append(bounds[-1] + size + (1 if j < extra else 0))
    return [range(bounds[j], bounds[j + 1]) for j in range(k)]


class IsolatedRunner:
    """Evaluate points in ``workers`` isolated, persistent worker processes (see module doc).

    timeout_s: longest wait for one point's result (s), None for no limit. grace_s: time
    between SIGTERM and SIGKILL for a worker being stopped (s). isolate_vectorized: also send
    models with ``modal_batch`` (NumPy models) to workers; if False they are evaluated in the
    caller. fresh_after_failure: replace a worker after a failed evaluation. retries: how
    often a point whose worker died is tried again in a fresh worker. ``stats`` counts worker
    starts ("started"), deaths ("crashed"), stops on timeout ("timed_out") and replacements
    after a failure ("retired"). Calls from several threads are serialized. Where workers are
    spawned (no fork), a worker's start-up counts toward its first point's timeout.
    """

    def __init__(
        self,
        workers: int = 1,
        timeout_s: float | None = None,
        *,
        grace_s: float = 1.0,
        isolate_vectorized: bool = True,
        fresh_after_failure: bool = True,
        retries: int = 1,
    ):
        if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
            raise ValueError(f"workers must be an integer >= 1, got {workers!r}")
        if timeout_s is not None and not (isinstance(timeout_s, int | float) and math.isfinite(timeout_s)
                                          and timeout_s > 0):
            raise ValueError(f"timeout_s must be a finite number > 0 or None, got {timeout_s!r}")
        if not (math.isfinite(grace_s) and grace_s >= 0):
            raise ValueError(f"grace_s must be a finite number >= 0, got {grace_s!r}")
        if retries < 0:
            raise ValueError(f"retries must be >= 0, got {retries!r}")
        self.workers = workers
        self.timeout_s = None if timeout_s is None else float(timeout_s)
        self.grace_s = float(grace_s)
        self.isolate_vectorized = isolate_vectorized
        self.fresh_after_failure = fresh_after_failure
        self.retries = retries
        self._setup()

    def _setup(self) -> None:
        self._slots: list[_Worker | None] = []
        self._lock = threading.RLock()
        self.stats: Counter[str] = Counter()
        # stop the workers when the runner is garbage-collected or at interpreter exit
        self._finalizer = weakref.finalize(self, stop_workers, self._slots, self.grace_s)

    def __getstate__(self):
        return {k: getattr(self, k) for k in ("workers", "timeout_s", "grace_s", "isolate_vectorized",
                                               "fresh_after_failure", "retries")}

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._setup()

    def __repr__(self) -> str:
        return f"{type(self).__name__}(workers={self.workers}, timeout_s={self.timeout_s})"

    def close(self) -> None:
        """Stop and reap every worker (the runner can be used again; it starts new ones)."""
        with self._lock:
            stop_workers(self._slots, self.grace_s)

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __call__(self, model, thetas: Sequence[Mapping[str, float]]) -> list:
        thetas = [dict(theta) for theta in thetas]
        if not thetas:
            return []
        batch = getattr(model, "modal_batch", None) is not None
        if batch and not self.isolate_vectorized:
            return modal_many(model, thetas)
        try:
            blob = pickle.dumps(model, protocol=pickle.HIGHEST_PROTOCOL)
        except Exception as exc:
            raise TypeError(f"model {type(model).__name__} cannot be sent to an isolated worker "
                            f"(not picklable: {exc}); define its build function at module level") from exc
        with self._lock:
            try:
                return self._evaluate(blob, thetas, batch)
            except BaseException:  # Ctrl-C or a worker that cannot load the model: no stale answers later
                stop_workers(self._slots, 0.0)
                raise

    # ---- scheduling -----------------------------------------------------------------------
    def _evaluate(self, blob: bytes, thetas: list[dict], batch: bool) -> list:
        n = len(thetas)
        k = min(self.workers, n)
        self._slots.extend([None] * (k - len(self._slots)))
        shares = [_Share(slot, indices, batch) for slot, indices in enumerate(split(n, k))]
        results: list = [None] * n
        deaths: Counter[int] = Counter()
        while True:
            for share in shares:
                if share.queue and not share.in_flight:
                    self._dispatch(share, blob, thetas)
            busy = [s for s in shares if s.in_flight]
            if not busy:
                return results
            now = time.monotonic()
            wait_s = min([POLL_S] + [max(0.0, s.deadline - now) for s in busy if s.deadline is not None])
            wait([self._slots[s.slot].conn for s in busy], wait_s)
            for share in busy:
                worker = self._slots[share.slot]
                if worker.conn.poll():  # a message, or the end of the pipe
                    self._receive(share, worker, results, deaths)
                elif worker.poll():  # ended without closing the pipe (a grandchild keeps it open)
                    self._died(share, worker, results, deaths)
                elif share.deadline is not None and time.monotonic() >= share.deadline:
                    self._timed_out(share, worker, results)

    def _deadline(self, n_points: int) -> float | None:
        return None if self.timeout_s is None else time.monotonic() + self.timeout_s * n_points

    def _dispatch(self, share: _Share, blob: bytes, thetas: list[dict]) -> None:
        worker = self._slots[share.slot]
        if worker is not None and worker.poll():  # died while idle: not the fault of any point
            log.info("idle evaluation worker %d %s; starting a new one", worker.pid,
                     exit_description(worker.exitcode))
            worker.reap(0.0)
            worker = None
        for _ in range(2):
            if worker is None:
                worker = _Worker()
                self.stats["started"] += 1
                self._slots[share.slot] = worker
            items = [(i, thetas[i]) for i in share.queue]
            message = ("run", None if worker.model_blob == blob else blob, items, share.batch,
                       self.fresh_after_failure)
            try:
                worker.conn.send(message)
            except OSError:  # the pipe broke: the worker ended just now
                worker.kill(0.0)
                worker = self._slots[share.slot] = None
                continue
            worker.model_blob = blob
            share.in_flight, share.queue = share.queue, deque()
            share.deadline = self._deadline(len(items) if share.batch else 1)
            return
        raise RuntimeError("could not start an isolated evaluation worker")

    def _receive(self, share: _Share, worker: _Worker, results: list, deaths: Counter) -> None:
        try:
            message = worker.conn.recv()
        except (EOFError, OSError):
            self._died(share, worker, results, deaths)
            return
        kind = message[0]
        if kind == "done":
            _, i, payload = message
            results[i] = _decode(payload)
            if share.in_flight and share.in_flight[0] == i:
                share.in_flight.popleft()
            else:  # pragma: no cover - answers come in the order sent
                share.in_flight.remove(i)
            share.deadline = self._deadline(1)
        elif kind == "batch":
            for i, payload in message[1]:
                results[i] = _decode(payload)
            share.in_flight.clear()
            share.deadline = None
        elif kind == "retire":  # a point failed: continue in a process where nothing failed
            worker.reap(time.monotonic() + self.grace_s)
            self._slots[share.slot] = None
            self.stats["retired"] += 1
            share.requeue([])
        elif kind == "fatal":
            raise RuntimeError(message[1])
        else:  # pragma: no cover - protocol error
            raise RuntimeError(f"unexpected message from an evaluation worker: {kind!r}")

    def _died(self, share: _Share, worker: _Worker, results: list, deaths: Counter) -> None:
        worker.kill(self.grace_s)  # normally already ended: this only reaps it
        how = exit_description(worker.exitcode)
        self._slots[share.slot] = None
        self.stats["crashed"] += 1
        if share.batch:  # the share was evaluated as one batch: redo it point by point
            log.warning("evaluation worker %s during a batch of %d points; redoing them one by one", how,
                        len(share.in_flight))
            share.batch = False
            share.requeue([])
            return
        i = share.in_flight.popleft()
        deaths[i] += 1
        if deaths[i] > self.retries:
            results[i] = ModelEvaluationError("worker_crashed", f"evaluation worker {how}")
            log.warning("evaluation worker %s at point %d, also in a fresh worker; recorded as failed", how, i)
            share.requeue([])
        else:
            log.warning("evaluation worker %s at point %d; trying it again in a fresh worker", how, i)
            share.requeue([i])

    def _timed_out(self, share: _Share, worker: _Worker, results: list) -> None:
        worker.kill(self.grace_s)
        self._slots[share.slot] = None
        self.stats["timed_out"] += 1
        if share.batch:
            limit = self.timeout_s * len(share.in_flight)
            for i in share.in_flight:
                results[i] = ModelEvaluationError("timeout", f"batch of {len(share.in_flight)} points "
                                                             f"not done after {limit:g} s; worker stopped")
            share.in_flight.clear()
            share.deadline = None
            return
        i = share.in_flight.popleft()
        results[i] = ModelEvaluationError("timeout", f"no result after {self.timeout_s:g} s; worker stopped")
        log.warning("evaluation of point %d took more than %g s; worker stopped", i, self.timeout_s)
        share.requeue([])

