"""Parallel multi-start of the sensitivity method, with early stopping of hopeless starts.

``n_starts`` start points are drawn in the normalized box from the run's seed
(:func:`framework.optimizers.sampling.sample`: Sobol' by default; optionally the initial
model first). Each start is one SM run (:mod:`framework.optimizers.sm`, ``local`` settings)
from that point; the result is the best point over all starts.

Design. The starts are independent, so whole SM sub-runs are farmed out, not single model
evaluations: the adapter maps a pure function ``run_start(task) -> StartResult`` over the
starts with :func:`framework.execution.parallel.map_unordered` on the backend of the run's evaluation
runner (the ``execution.evaluation_backend`` of a study):

- serial (``modal_many`` or an isolated serial runner): in this process, evaluating through
  the run's runner;
- processes (:class:`~framework.execution.parallel.ProcessRunner`): a pool of as many processes as
  the runner has workers; each start evaluates in its process, isolated in a child process
  (with the runner's per-evaluation timeout) as the runner would;
- Dask (:class:`~framework.execution.parallel.DaskRunner`): one task per start on the runner's cluster
  (``worker_client`` when the run itself is a Dask task), isolated if the runner is.

Each start has its own :class:`~framework.updating.evaluator.Evaluator`; its record (count, values,
failures, best point) comes back as plain data and is merged into the run's evaluator
(``Evaluator.merge``) in start order, so the count, the history and the best point are
those of a serial run.

Determinism. The results are identical whatever the backend and worker count: the start
points depend on the seed only; starts are processed in fixed batches of ``batch_size``
(not of the worker count); every decision (the budget of each start, early stopping, the
end of the run) uses only the results of *earlier batches*, which are merged in start order
once the whole batch is back.

Budget. Before each batch, each of its starts is given the evaluations left divided by the
starts not yet run, but at least ``min_evaluations_per_start`` (default k + 2) and at most
``max_evaluations_per_start``, and no more than the batch can share; evaluations saved by
early stopping roll over to later starts. A start runs under the run's termination rule
with that budget. If the target objective is met, no further batch is started (status
"target"); when a batch cannot give each start its minimum, it and the later starts are
"not_run" (status "budget").

Early stopping (``early_stop``). Let the incumbent P* be the best objective found by the
earlier batches. A start is stopped as soon as it has spent ``check_evaluations`` model
evaluations (default 3 (k + 1): three forward-difference SM iterations for k parameters,
more iterations where the Jacobian costs less) and its best objective so far is still
above ``stop_factor`` x P* (default 10). The first batch is never stopped (no incumbent
yet). Why this rule: it costs no extra model evaluation and uses only numbers known before
the batch (deterministic). A Gauss-Newton bound (||r||^2 - ||J dx||^2 from the linearized
model) would need a Jacobian first and bounds only the linearized model, not the true
objective, so it is no safer. The sensitivity method decreases the objective monotonically
and converges fast (superlinearly near a small-residual minimum), so a start in the basin
of a minimum as good as the incumbent's is typically far below 10 P* after three
iterations. It is a heuristic: a start that would reach a better minimum only slowly can
be stopped, and so is a start that would only find the incumbent's minimum again (it
cannot beat it by more than the solver's tolerances); raise ``stop_factor`` or
``check_evaluations`` (or set ``early_stop: false``) when in doubt, and compare.

Reported (``extra``; one row per key in the updating kind's ``extra`` table): ``start_1``,
... (start point, objective, best point, evaluations, iterations, SM status or
"stopped_early"/"not_run", batch, budget, ``stop_threshold`` = stop_factor x P*), ``condition_number``
of the best start, and ``run_columns`` (``n_starts_run``, ``n_stopped_early``,
``best_start``) for the runs table. A start whose worker fails (not a failed model
evaluation, which is recorded as usual) ends the run with an error.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from pydantic import Field, field_serializer, field_validator

from framework.core.status import Status
from framework.optimizers import sm
from framework.optimizers.base import Budget, Optimizer, Outcome, Settings
from framework.optimizers.hybrid import local_settings, polish_from, without_start
from framework.optimizers.sampling import Sampler, sample
from framework.updating.evaluator import BudgetExhausted, EvaluationRecord, Evaluator


class MultiStartSettings(Settings):
    n_starts: int = Field(20, ge=1)
    sampler: Sampler = "sobol"
    include_initial: bool = False
    batch_size: int = Field(4, ge=1)
    max_evaluations_per_start: int | None = Field(None, gt=0)
    min_evaluations_per_start: int | None = Field(None, gt=0)
    early_stop: bool = True
    stop_factor: float = Field(10.0, gt=1)
    check_evaluations: int | None = Field(None, gt=0)
    local: sm.SMSettings = Field(default_factory=dict, validate_default=True)

    @field_validator("local", mode="before")
    @classmethod
    def _local(cls, v):
        return local_settings(v, "local", "the multi-start (each start has its own point)")

    @field_serializer("local", mode="wrap")
    def _dump(self, settings, handler):
        return without_start(settings, handler)


class StartDominated(BudgetExhausted):
    """Raised in a start's evaluator when the early-stopping rule stops the start."""


class _WatchedEvaluator(Evaluator):
    """A start's evaluator that stops the start by the early-stopping rule (module docstring)."""

    def __init__(self, problem, max_evaluations, runner, check_evaluations: int | None, threshold: float):
        super().__init__(problem, max_evaluations, runner=runner)
        self.check_evaluations = check_evaluations
        self.threshold = threshold
        self.stopped = False

    def evaluate(self, X):
        if (self.check_evaluations is not None and self.n_evaluations >= self.check_evaluations
                and not self.best_objective <= self.threshold):
            self.stopped = True
            raise StartDominated(f"best {self.best_objective:.4g} above {self.threshold:.4g} after "
                                 f"{self.n_evaluations} evaluations")
        return super().evaluate(X)


@dataclass(frozen=True)
class StartTask:
    """Everything one start needs (picklable): the problem, its start point and budget, the
    SM settings, the early-stopping threshold (inf: none) and how to evaluate the model."""

    index: int
    problem: object
    x0: np.ndarray
    seed: int
    budget: Budget
    local: sm.SMSettings
    check_evaluations: int | None
    threshold: float
    isolate: tuple | None  # (timeout_s, isolate_vectorized) of a 1-worker IsolatedRunner, or None
    runner: object = None  # the serial path's runner (never sent to a worker)


@dataclass(frozen=True)
class StartResult:
    index: int
    record: EvaluationRecord
    status: str
    n_iterations: int
    extra: dict
    stopped: bool


def run_start(task: StartTask) -> StartResult:
    """One SM start (a pure function of the task; runs in any process)."""
    runner, close = task.runner, None
    if task.isolate is not None:
        from framework.execution.isolation import IsolatedRunner

        timeout_s, isolate_vectorized = task.isolate
        runner = IsolatedRunner(1, timeout_s, isolate_vectorized=isolate_vectorized)
        close = runner.close
    try:
        ev = _WatchedEvaluator(task.problem, task.budget.max_evaluations, runner, task.check_evaluations,
                               task.threshold)
        out = sm.run(ev, task.seed, task.budget, polish_from(task.local, task.x0))
    finally:
        if close is not None:
            close()
    status = "stopped_early" if ev.stopped else out.status
    return StartResult(task.index, ev.export(), status, out.n_iterations, out.extra, ev.stopped)


def _backend(runner) -> tuple[str, int, object, tuple | None]:
    """(backend, workers, Dask client or None, isolation of each start) of the run's runner;
    anything else than a ProcessRunner or DaskRunner (``modal_many``, an isolated serial
    runner) is the serial backend, which evaluates through the runner itself."""
    from framework.execution.parallel import DaskRunner, ProcessRunner

    if isinstance(runner, ProcessRunner):
        return "processes", runner.workers, None, (runner.timeout_s, True)
    if isinstance(runner, DaskRunner):
        isolation = (runner.timeout_s, runner.isolate_vectorized) if runner.isolate else None
        return "dask", 0, runner.client, isolation
    return "serial", 1, None, None


def _map(tasks: list[StartTask], runner) -> list[StartResult]:
    """Run the tasks on the backend of ``runner``; results in task order."""
    from framework.execution.parallel import map_unordered

    backend, workers, client, isolation = _backend(runner)
    if backend == "serial":
        tasks = [_with(t, runner=runner) for t in tasks]
        out = [run_start(t) for t in tasks]
    elif backend == "processes":
        tasks = [_with(t, isolate=isolation) for t in tasks]
        out = _collect(map_unordered(run_start, tasks, backend="processes", workers=workers), len(tasks))
    else:
        tasks = [_with(t, isolate=isolation) for t in tasks]
        if client is None:
            from distributed import worker_client

            with worker_client() as own:
                out = _collect(map_unordered(run_start, tasks, backend="dask", client=own), len(tasks))
        else:
            out = _collect(map_unordered(run_start, tasks, backend="dask", client=client), len(tasks))
    return out


def _with(task: StartTask, **changes) -> StartTask:
    from dataclasses import replace

    return replace(task, **changes)


def _collect(pairs, n: int) -> list:
    out: list = [None] * n
    for i, result in pairs:
        if isinstance(result, BaseException):
            raise RuntimeError(f"multistart: start {i + 1} failed in its worker: {type(result).__name__}: "
                               f"{result}") from result
        out[i] = result
    return out


def run(evaluator, seed: int, budget: Budget, s: MultiStartSettings) -> Outcome:
    k = evaluator.n_params
    params = evaluator.parameters
    starts = sample(s.n_starts, k, seed, s.sampler)
    if s.include_initial:
        starts[0] = evaluator.x_initial
    check = s.check_evaluations or 3 * (k + 1)
    minimum = s.min_evaluations_per_start or (k + 2)
    records: list[dict] = [
        {"start": i + 1, "x_start": x.tolist(), "theta_start": params.to_physical(x).tolist()}
        for i, x in enumerate(starts)
    ]
    incumbent = np.inf
    best_i, best_extra, best_status = None, {}, Status.BUDGET
    iterations = 0
    reason = None
    for b0 in range(0, s.n_starts, s.batch_size):
        batch = range(b0, min(b0 + s.batch_size, s.n_starts))
        remaining = evaluator.remaining
        share = max(int(remaining // (s.n_starts - b0)), minimum)
        if s.max_evaluations_per_start is not None:
            share = min(share, s.max_evaluations_per_start)
        share = min(share, int(remaining // len(batch)))
        if share < minimum:
            reason = Status.BUDGET
            break
        threshold = s.stop_factor * incumbent if s.early_stop and np.isfinite(incumbent) else np.inf
        tasks = [
            StartTask(i, evaluator.problem, starts[i], seed, budget.model_copy(update={"max_evaluations": share}),
                      s.local, check if np.isfinite(threshold) else None, float(threshold), None)
            for i in batch
        ]
        for res in _map(tasks, evaluator.runner):
            evaluator.merge(res.record)
            rec = res.record
            objective = float(rec.best_objective) if rec.best_x is not None else None
            records[res.index].update({
                "objective": objective,
                "x_best": None if rec.best_x is None else np.asarray(rec.best_x).tolist(),
                "theta_best": None if rec.best_x is None else params.to_physical(rec.best_x).tolist(),
                "n_evaluations": rec.n_evaluations, "n_iterations": res.n_iterations, "status": res.status,
                "batch": b0 // s.batch_size + 1, "budget": share,
                "stop_threshold": float(threshold) if np.isfinite(threshold) else None,
            })
            iterations += res.n_iterations
            if objective is not None and objective < incumbent:
                incumbent, best_i, best_extra, best_status = objective, res.index, res.extra, res.status
        if budget.target_objective is not None and incumbent < budget.target_objective:
            reason = Status.TARGET
            break
    for r in records:
        r.setdefault("status", "not_run")
    n_run = sum(r["status"] != "not_run" for r in records)
    n_stopped = sum(r["status"] == "stopped_early" for r in records)
    status = reason or (best_status if best_i is not None else Status.BUDGET)
    if reason is None and n_run < s.n_starts:
        status = Status.BUDGET
    extra: dict[str, Any] = {f"start_{r['start']}": r for r in records}
    if "condition_number" in best_extra:
        extra["condition_number"] = best_extra["condition_number"]
    extra["run_columns"] = {"n_starts_run": n_run, "n_stopped_early": n_stopped,
                            "best_start": best_i + 1 if best_i is not None else 0}
    message = (f"{n_run} of {s.n_starts} starts run, {n_stopped} stopped early"
               + (f"; best from start {best_i + 1}" if best_i is not None else ""))
    return Outcome(status, iterations, message=message, extra=extra)


OPTIMIZER = Optimizer("multistart", MultiStartSettings, run)
