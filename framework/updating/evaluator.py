"""The per-run evaluator: what one optimizer run has evaluated, and what it may still spend.

An :class:`Evaluator` wraps a (stateless) problem for one run, like pymoo's ``Evaluator``:
``run_optimizer`` creates one per run and gives it to the adapter, which sees the problem
only through it. It counts model evaluations (a problem point costs
``problem.evaluations_per_point`` of them: 1, or 2 for a two-state point), keeps the
best point over the *successful* evaluations only (a failed point is never a result,
whatever its penalty), the best-so-far history per model evaluation, the failure
reasons (a Counter and one example message each) and the budget: an evaluation that
would exceed ``max_evaluations`` raises :class:`BudgetExhausted` before any model runs,
and ``affords(n)`` / ``remaining`` let an adapter plan. ``progress(n_new)`` is called
with the number of new model evaluations (e.g. a progress bar).

Jacobians (``evaluator.jacobian(x)``, used by the sensitivity method) are counted too:
an exact Jacobian (modal derivatives, :meth:`framework.updating.problem.UpdatingProblem.jacobian`)
adds its cost in eigen-solve equivalents (see :mod:`framework.core.modal_derivatives`) to
``n_evaluations`` and enters the history as that many evaluations without a new value; a
finite-difference Jacobian is its k model evaluations, recorded like any other.
``n_evaluations`` is therefore model evaluations + Jacobian equivalents; ``n_jacobians``
counts the Jacobians of either kind and ``jacobian_equivalents`` the equivalents alone.
The point of the last single-point evaluation is remembered with the model's result, so a
Jacobian at that point (least squares asks for one right after evaluating it) does not
solve the model again.

A child evaluator (``evaluator.child(problem, max_evaluations)``) serves a sub-search on a
transformed problem (SNT's derated objective): it has its own best point and budget, and
every evaluation also counts in the parent, which records the untransformed values
(``Evaluations.source``). A sub-run evaluated in another process (the starts of a
multi-start) is counted with ``evaluator.merge(sub.export())``.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from framework.updating.problem import Evaluations, Runner, as_points, fd_points


@dataclass(frozen=True)
class EvaluationRecord:
    """An evaluator's record as plain data: model evaluations, objective per evaluated point
    (NaN where it failed), failure counts and examples, failed points (bytes of x), best point."""

    n_evaluations: int
    values: np.ndarray
    failures: dict[str, int]
    failure_examples: dict[str, str]
    failed: frozenset
    best_x: np.ndarray | None
    best_objective: float


def concat_evaluations(parts: list[Evaluations]) -> Evaluations:
    """Evaluations of single points stacked into one (the pointwise path)."""
    sources = [e.source for e in parts]
    return Evaluations(
        objective=np.concatenate([e.objective for e in parts]),
        residuals=np.vstack([e.residuals for e in parts]),
        objectives=np.vstack([e.objectives for e in parts]),
        ok=np.concatenate([e.ok for e in parts]),
        reasons=[r for e in parts for r in e.reasons],
        details=[d for e in parts for d in e.details],
        correlations=[c for e in parts for c in e.correlations],
        source=None if any(s is None for s in sources) else concat_evaluations(sources),
    )


class BudgetExhausted(Exception):
    """Raised before an evaluation that would exceed the run's evaluation budget."""


class Evaluator:
    """Counted, budgeted access to ``problem.evaluate`` for one optimizer run."""

    def __init__(
        self,
        problem,
        max_evaluations: int | None = None,
        runner: Runner | None = None,
        progress: Callable[[int], object] | None = None,
        parent: Evaluator | None = None,
        pointwise: bool = False,
    ):
        self.problem = problem
        #: evaluate a population one point per call (as the source's toolboxes did; for timing)
        self.pointwise = pointwise if parent is None else parent.pointwise
        self.max_evaluations = max_evaluations
        self.runner = runner if parent is None else parent.runner
        self.progress = progress
        self.parent = parent
        self.cost = int(getattr(problem, "evaluations_per_point", 1))
        self.n_evaluations = 0  # model evaluations
        self.failures: Counter[str] = Counter()
        self.failure_examples: dict[str, str] = {}
        self.best_x: np.ndarray | None = None
        self.best_objective = np.inf
        self._values: list[np.ndarray] = []  # objective per evaluated point, NaN where it failed
        self._failed: set[bytes] = set()
        self.n_jacobians = 0
        self.jacobian_equivalents = 0  # eigen-solve equivalents of exact Jacobians
        self.jacobian_methods: Counter[str] = Counter()  # "exact" / "fd" / "failed"
        self._last: tuple[bytes, object, np.ndarray] | None = None  # last single point: (x, result, residuals)

    # ---- facts of the problem ---------------------------------------------------------
    @property
    def n_params(self) -> int:
        return self.problem.n_params

    @property
    def n_objectives(self) -> int:
        return int(getattr(self.problem, "n_objectives", 1))

    @property
    def parameters(self):
        return self.problem.parameters

    @property
    def x_initial(self) -> np.ndarray:
        return self.problem.x_initial

    # ---- budget ---------------------------------------------------------------------------
    @property
    def remaining(self) -> float:
        """Model evaluations left (inf without a budget); a child is also bound by its parent."""
        own = np.inf if self.max_evaluations is None else self.max_evaluations - self.n_evaluations
        return min(own, self.parent.remaining) if self.parent is not None else own

    def affords(self, n_points: int) -> bool:
        """True if ``n_points`` points can still be evaluated within the budget."""
        return n_points * self.cost <= self.remaining

    def child(self, problem, max_evaluations: int | None = None) -> Evaluator:
        """Evaluator of a sub-search on ``problem`` (a transform of this one) that counts here too."""
        return Evaluator(problem, max_evaluations, parent=self)

    # ---- evaluation -----------------------------------------------------------------------
    def evaluate(self, X: np.ndarray) -> Evaluations:
        """Evaluate points X (n, k), counted; raises BudgetExhausted if they do not fit."""
        X = as_points(X, self.n_params)
        if not self.affords(len(X)):
            raise BudgetExhausted(f"{len(X)} point(s) do not fit the {self.remaining} evaluations left")
        if len(X) == 1 and self.cost == 1 and hasattr(self.problem, "jacobian"):
            ev = self.problem.evaluate(X, self.runner, keep_results=True)
            self._last = (X[0].tobytes(), ev.results[0], ev.residuals[0])
        elif self.pointwise and len(X) > 1:
            ev = concat_evaluations([self.problem.evaluate(X[i:i + 1], self.runner) for i in range(len(X))])
        else:
            ev = self.problem.evaluate(X, self.runner)
        self._record(X, ev)
        return ev

    def jacobian(self, x: np.ndarray, fd_step: float = 1e-3) -> np.ndarray:
        """Jacobian dr/dx (r, k) at x, counted: exact when the problem has one (its cost in
        eigen-solve equivalents), else forward differences with step ``fd_step`` in x (k model
        evaluations). Evaluates x first unless it was the last single point evaluated."""
        x = as_points(np.asarray(x, float)[None, :], self.n_params)[0]
        if self._last is not None and self._last[0] == x.tobytes():
            _, result, r0 = self._last
        else:
            ev = self.evaluate(x[None, :])
            result, r0 = (ev.results[0] if ev.results else None), ev.residuals[0]
        problem = self.problem
        if getattr(problem, "has_exact_jacobian", False) and self.cost == 1:
            if problem.jacobian_cost_bound > self.remaining:
                raise BudgetExhausted(f"a Jacobian does not fit the {self.remaining} evaluations left")
            jac = problem.jacobian(x, self.runner, result, fd_step=fd_step, fallback=False)
            if jac.J is not None:
                self._record_cost(jac.cost)
                self.count_jacobians(jac.method)
                return jac.J
        X, h = fd_points(x, fd_step)
        fd = self.evaluate(X)
        self.count_jacobians("fd")
        return (fd.residuals - r0[None, :]).T / h[None, :]

    def count_jacobians(self, method: str, n: int = 1) -> None:
        """Count n Jacobians of kind ``method`` here and in every parent (as evaluations are)."""
        self.n_jacobians += n
        self.jacobian_methods[method] += n
        if self.parent is not None:
            self.parent.count_jacobians(method, n)

    def _record_cost(self, n: int) -> None:
        """Count n evaluation equivalents that bring no new objective value (an exact Jacobian)."""
        if n <= 0:
            return
        self.n_evaluations += n
        self.jacobian_equivalents += n
        self._values.append(np.full(n, np.nan))
        if self.parent is not None:
            self.parent._record_cost(n)
        elif self.progress is not None:
            self.progress(n)

    def _record(self, X: np.ndarray, ev: Evaluations) -> None:
        n_new = len(X) * self.cost
        self.n_evaluations += n_new
        values = np.where(ev.ok, ev.objective, np.nan)
        self._values.append(values)
        for x, reason, detail in zip(X, ev.reasons, ev.details):
            if reason is not None:
                self.failures[reason] += 1
                self.failure_examples.setdefault(reason, detail)
                self._failed.add(np.asarray(x, float).tobytes())
        if np.any(ev.ok):
            i = int(np.nanargmin(values))
            if values[i] < self.best_objective:
                self.best_objective = float(values[i])
                self.best_x = np.array(X[i], dtype=float)
        if self.parent is not None:
            self.parent._record(X, ev.source if ev.source is not None else ev)
        elif self.progress is not None:
            self.progress(n_new)

    # ---- evaluations made elsewhere (a sub-run in a worker process) -------------------------
    def export(self) -> EvaluationRecord:
        """What this evaluator recorded, as plain picklable data (see :meth:`merge`)."""
        values = np.concatenate(self._values) if self._values else np.array([])
        return EvaluationRecord(self.n_evaluations, values, dict(self.failures), dict(self.failure_examples),
                                frozenset(self._failed), self.best_x, float(self.best_objective))

    def merge(self, record: EvaluationRecord) -> None:
        """Count a sub-run evaluated elsewhere (e.g. an SM start on another worker) as this run's
        evaluations, as if they had been made here in that order (count, history, best point,
        failures; the parent chain and progress too). Its budget was checked where it ran."""
        self.n_evaluations += record.n_evaluations
        self._values.append(np.asarray(record.values, float))
        self.failures.update(record.failures)
        for reason, example in record.failure_examples.items():
            self.failure_examples.setdefault(reason, example)
        self._failed |= record.failed
        if record.best_x is not None and record.best_objective < self.best_objective:
            self.best_objective = float(record.best_objective)
            self.best_x = np.array(record.best_x, dtype=float)
        if self.parent is not None:
            self.parent.merge(record)
        elif self.progress is not None and record.n_evaluations:
            self.progress(record.n_evaluations)

    # the three views used by the adapters
    def objective(self, X: np.ndarray) -> np.ndarray:
        """Scalar objective Pi of each row of X (n, k) -> (n,)."""
        return self.evaluate(X).objective

    def objective1(self, x: np.ndarray) -> float:
        """Scalar objective of one point x (k,)."""
        return float(self.evaluate(np.asarray(x, float)[None, :]).objective[0])

    def residuals(self, x: np.ndarray) -> np.ndarray:
        """Residual vector of one point (sum of squares = Pi)."""
        return self.evaluate(np.asarray(x, float)[None, :]).residuals[0]

    def objectives(self, X: np.ndarray) -> np.ndarray:
        """Objective vectors (n, n_objectives) of the rows of X."""
        return self.evaluate(X).objectives

    # ---- what the run did -----------------------------------------------------------------
    @property
    def n_failed(self) -> int:
        """Number of failed points."""
        return sum(self.failures.values())

    @property
    def has_success(self) -> bool:
        return self.best_x is not None

    def is_failed(self, x: np.ndarray) -> bool:
        """True if the point x (as evaluated, in [0, 1]^k) failed in this run."""
        return np.clip(np.asarray(x, float), 0.0, 1.0).tobytes() in self._failed

    def history(self) -> np.ndarray:
        """Best objective so far after each model evaluation (NaN before the first success).

        A point that costs c model evaluations is known after the last of them: its value
        enters the history at that evaluation.
        """
        if not self._values:
            return np.array([])
        best = np.fmin.accumulate(np.concatenate(self._values))
        if self.cost == 1:
            return best
        before = np.r_[np.nan, best[:-1]]
        return np.column_stack([np.repeat(before[:, None], self.cost - 1, axis=1), best[:, None]]).ravel()

    def failure_summary(self) -> str:
        return "; ".join(f"{k} x{v} ({self.failure_examples[k]})" for k, v in sorted(self.failures.items()))
