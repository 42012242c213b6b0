"""What every optimizer adapter shares: the :class:`Optimizer` object, settings, budget,
termination rule, outcome, result, seeding.

An optimizer is one :class:`Optimizer` object (name, pydantic :class:`Settings` class, adapter
``run(evaluator, seed, budget, settings) -> Outcome``). Its settings are validated once, where
they are read (:meth:`Optimizer.validate` for a config), and reach the adapter as that typed
object. The adapter sees the problem only through the run's :class:`~framework.updating.evaluator.Evaluator`
(``objective(X)``, ``objective1(x)``, ``residuals(x)``, ``objectives(X)``, ``n_params``,
``parameters``, ``x_initial``), which counts, budgets and remembers the evaluations;
``run_optimizer`` builds the :class:`OptimizerResult` from the evaluator and the outcome.

Termination (SPEC 4, lab study), one :class:`Termination` object per run: stop when the
best value improved by less than ``stall_tolerance`` over ``stall_iterations`` successive
iterations ("stalled"), or the best value is below ``target_objective`` ("target"), or
``max_iterations`` iterations were done ("max_iterations"), or the next iteration would
exceed ``max_evaluations`` model evaluations ("budget"). Each adapter reports its best
value after every iteration and stops when told.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from framework.core.status import Status
from framework.updating.evaluator import BudgetExhausted  # noqa: F401  (re-exported for the adapters)


class Budget(BaseModel):
    """Evaluation budget and the termination rule shared by the optimizers (finite numbers only)."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    max_evaluations: int = Field(50_000, gt=0)
    stall_iterations: int = Field(10, gt=0)
    stall_tolerance: float = Field(1e-8, ge=0)
    target_objective: float | None = 1e-6
    max_iterations: int | None = Field(None, gt=0)


class Settings(BaseModel):
    """Base of every optimizer's settings: unknown keys and non-finite numbers are rejected."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


def first_problem(exc: ValidationError) -> tuple[str, str]:
    """(field path, problem) of the first error of a settings validation; the problem names the
    value given. A message of a nested settings' own validator already starts with its path."""
    first = exc.errors()[0]
    path = ".".join(str(p) for p in first["loc"])
    msg = first["msg"].removeprefix("Value error, ")
    if first["type"] == "value_error":
        if path and msg.startswith(path) and ": " in msg:
            return tuple(msg.split(": ", 1))
        return path, msg
    if first["type"] == "extra_forbidden":
        msg = "unknown key"
    return path, f"{msg} (value {first.get('input')!r})"


@dataclass(frozen=True)
class Optimizer:
    """One optimization method: its name, its settings class and its adapter.

    ``run(evaluator, seed, budget, settings) -> Outcome`` gets the settings as an instance of
    ``settings``, validated once where they were read: :meth:`validate` for settings read from
    a config (strict types, as every config value), :func:`framework.optimizers.run_optimizer`
    for keywords given in code.
    """

    name: str
    settings: type[Settings]
    run: Callable[[Any, int, Budget, Settings], Outcome]

    def validate(self, data: Mapping[str, Any] | Settings, where: str = "settings") -> Settings:
        """The settings of a config (strict); ValueError ``<where>.<field>: <problem> (value ...)``."""
        if isinstance(data, self.settings):
            return data
        try:
            return self.settings.model_validate(data, strict=True)
        except ValidationError as exc:
            path, problem = first_problem(exc)
            raise ValueError(f"{'.'.join(filter(None, (where, path)))}: {problem}") from None


@dataclass
class OptimizerResult:
    """Outcome of one optimizer run (x in [0, 1]^k, theta in physical units).

    n_evaluations counts model evaluations (a two-state point counts 2) plus the
    eigen-solve equivalents of exact Jacobians (see :mod:`framework.updating.evaluator`); n_jacobians
    counts Jacobians (exact or finite-difference); history is the best successful objective
    after each evaluation (NaN before the first success); extra is plain JSON data.
    status "failed": no evaluation succeeded, and x_best, theta_best and objective are NaN.
    """

    algorithm: str
    seed: int
    x_best: np.ndarray
    theta_best: np.ndarray
    objective: float
    n_evaluations: int
    n_iterations: int
    wall_s: float
    status: str
    message: str = ""
    history: np.ndarray = field(default_factory=lambda: np.array([]))
    n_failed: int = 0
    failures: str = ""
    extra: dict = field(default_factory=dict)
    n_jacobians: int = 0


@dataclass
class Outcome:
    """What an adapter reports: why it stopped, iterations, message, extra facts, and
    optionally its own choice of final point (NSGA-II, SNT); by default the final point is
    the evaluator's best successful point."""

    status: str
    n_iterations: int
    message: str = ""
    extra: dict = field(default_factory=dict)
    x_best: np.ndarray | None = None
    objective: float | None = None


class Termination:
    """The termination rule of one run (module docstring), fed the best value per iteration.

    ``rules``: which of "stall", "target", "max_iterations" apply (all by default; an
    adapter whose library does not expose iterations says which it can apply). The
    evaluation budget always applies, through ``affords``.
    """

    RULES = ("stall", "target", "max_iterations")

    def __init__(self, budget: Budget, evaluator, rules: tuple[str, ...] = RULES):
        unknown = set(rules) - set(self.RULES)
        if unknown:
            raise ValueError(f"unknown termination rule(s) {sorted(unknown)}; known: {list(self.RULES)}")
        self.budget = budget
        self.evaluator = evaluator
        self.rules = frozenset(rules)
        self.best = np.inf
        self.stalled = 0
        self.iterations = 0
        self.reason: str | None = None

    def affords(self, n_points: int) -> bool:
        """True if an iteration of ``n_points`` points fits in the evaluation budget."""
        return self.evaluator.affords(n_points)

    def update(self, best: float) -> str | None:
        """Record the best value after an iteration; return the stop reason or None."""
        self.iterations += 1
        improvement = self.best - best
        self.stalled = self.stalled + 1 if improvement < self.budget.stall_tolerance else 0
        self.best = min(self.best, best)
        b = self.budget
        if "target" in self.rules and b.target_objective is not None and self.best < b.target_objective:
            self.reason = Status.TARGET
        elif "stall" in self.rules and self.stalled >= b.stall_iterations:
            self.reason = Status.STALLED
        elif "max_iterations" in self.rules and b.max_iterations is not None and self.iterations >= b.max_iterations:
            self.reason = Status.MAX_ITERATIONS
        return self.reason

    @property
    def status(self) -> str:
        """The stop reason; "budget" if no rule fired (the adapter ran out of evaluations)."""
        return self.reason or Status.BUDGET


@contextlib.contextmanager
def seeded_global_numpy(seed: int):
    """Seed numpy's *global* generator for libraries that draw from it (pyswarms), then
    restore the previous state, so a run is reproducible from its seed and leaves no trace.
    Runs in one process are sequential; process and Dask workers each have their own state.
    """
    state = np.random.get_state()
    np.random.seed(seed % (2**32))
    try:
        yield
    finally:
        np.random.set_state(state)


def json_safe(value):
    """``value`` with numpy arrays and scalars turned into lists and Python numbers (for JSON)."""
    if isinstance(value, dict):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    if isinstance(value, np.ndarray):
        return json_safe(value.tolist())
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.floating):
        return float(value)
    return value


def build_result(algorithm: str, evaluator, seed: int, outcome: Outcome, wall_s: float) -> OptimizerResult:
    """The run's result from its evaluator and the adapter's outcome.

    The final point is the adapter's choice if it made one and that point did not fail,
    else the evaluator's best successful point. A run without any successful evaluation
    is ``status="failed"`` with NaN parameters and objective: a failed point is never a result.
    """
    x_best, objective = outcome.x_best, outcome.objective
    if x_best is not None and evaluator.is_failed(x_best):
        x_best = None
    if x_best is None:
        x_best, objective = evaluator.best_x, evaluator.best_objective
    status, message = outcome.status, outcome.message
    if x_best is None or not evaluator.has_success:
        x_best = np.full(evaluator.n_params, np.nan)
        objective = np.nan
        status = Status.FAILED
        what = "every evaluation failed" if evaluator.n_evaluations else "no evaluation was made"
        message = f"{what}: {evaluator.failure_summary()}" if evaluator.n_failed else what
    else:
        x_best = np.clip(np.asarray(x_best, float), 0.0, 1.0)
    return OptimizerResult(
        algorithm=algorithm,
        seed=seed,
        x_best=x_best,
        theta_best=evaluator.parameters.to_physical(x_best),
        objective=float(objective),
        n_evaluations=evaluator.n_evaluations,
        n_iterations=int(outcome.n_iterations),
        wall_s=float(wall_s),
        status=status,
        message=message,
        history=evaluator.history(),
        n_failed=evaluator.n_failed,
        failures=evaluator.failure_summary(),
        extra=json_safe(outcome.extra),
        n_jacobians=evaluator.n_jacobians,
    )
