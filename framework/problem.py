"""The updating problem: normalized x in [0, 1]^k -> physical theta -> model -> objective.

One definition, three views: ``objective(X)`` (scalar, for PSO/GA/annealing),
``residuals(x)`` (vector, for least squares / the sensitivity method) and
``objectives(X)`` (vector of objectives, for NSGA-II). Every model evaluation, including
those spent on finite-difference Jacobians, is counted and logged with its objective; a
failed evaluation becomes the documented penalty (see :mod:`framework.objectives`) and
its reason is recorded.

The model is evaluated through a *runner* ``runner(model, thetas) -> list`` (serial by
default; process pools and Dask in :mod:`framework.parallel`), so parallelism is plugged
in from outside and the problem itself stays a plain, picklable description.
"""

from __future__ import annotations

import logging
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from framework.errors import InputError, ModelEvaluationError
from framework.measurements import MeasuredModes
from framework.models.base import ModalResult, StructuralModel, modal_many
from framework.objectives import (
    ModeCorrelation,
    ObjectiveSpec,
    check_constraints,
    correlation_table,
    get_formulation,
    n_penalty_residuals,
    penalty_residuals,
)
from framework.parameters import ParameterSet

log = logging.getLogger(__name__)

Runner = Callable[[StructuralModel, Sequence[dict]], list]


@dataclass
class Evaluations:
    """Result of evaluating n points: objective (n,), residuals (n, r), ok (n,), reasons."""

    objective: np.ndarray
    residuals: np.ndarray
    ok: np.ndarray
    reasons: list[str | None]
    correlations: list[ModeCorrelation | None]


class EvaluationLog:
    """Counts evaluations and keeps the objective of each, in order, plus failure reasons."""

    def __init__(self) -> None:
        self.objectives: list[float] = []
        self.failures: Counter[str] = Counter()
        self.failure_examples: dict[str, str] = {}
        self.best_x: np.ndarray | None = None
        self.best_objective = np.inf
        self.on_record = None  # optional callback(n_new_evaluations), e.g. a progress bar

    @property
    def n_evaluations(self) -> int:
        return len(self.objectives)

    @property
    def n_failed(self) -> int:
        return sum(self.failures.values())

    def record(self, X: np.ndarray, objective: np.ndarray, reasons: list[str | None], details: list[str]) -> None:
        self.objectives.extend(float(v) for v in objective)
        for reason, detail in zip(reasons, details):
            if reason is not None:
                self.failures[reason] += 1
                self.failure_examples.setdefault(reason, detail)
        i = int(np.argmin(objective)) if len(objective) else -1
        if i >= 0 and objective[i] < self.best_objective:
            self.best_objective = float(objective[i])
            self.best_x = np.array(X[i], dtype=float)
        if self.on_record is not None:
            self.on_record(len(objective))

    def best_so_far(self) -> np.ndarray:
        return np.minimum.accumulate(np.asarray(self.objectives)) if self.objectives else np.array([])

    def failure_summary(self) -> str:
        return "; ".join(f"{k} x{v} ({self.failure_examples[k]})" for k, v in sorted(self.failures.items()))


class UpdatingProblem:
    """Model updating of ``model`` to ``measured`` over ``parameters`` (default: all of the model's)."""

    def __init__(
        self,
        model: StructuralModel,
        measured: MeasuredModes,
        parameters: ParameterSet | None = None,
        objective: ObjectiveSpec | None = None,
        runner: Runner | None = None,
        name: str = "",
    ):
        self.model = model
        self.measured = measured
        self.parameters = parameters if parameters is not None else model.parameters
        self.spec = objective if objective is not None else ObjectiveSpec()
        self.runner = runner
        self.name = name or getattr(model, "name", type(model).__name__)
        self.formulation = get_formulation(self.spec.formulation)
        check_constraints(self.parameters, self.spec)
        unknown_params = sorted(set(self.parameters.names) - set(model.parameters.names))
        if unknown_params:
            raise InputError(
                f"parameters {unknown_params} are not parameters of model {self.name!r}; "
                f"known: {model.parameters.names}"
            )
        if self.spec.use_shapes and measured.has_shapes:
            unknown = [d for d in measured.dofs if d not in model.dofs]
            if unknown:
                raise InputError(
                    f"{measured.source}: measured DOF(s) {unknown} are not DOFs of model {self.name!r}; "
                    f"model DOFs: {list(model.dofs)[:20]}"
                )
        self.n_modal_residuals = self.formulation.n_residuals(measured, self.spec)
        self.n_residuals = self.n_modal_residuals + n_penalty_residuals(self.parameters, self.spec)
        self.log = EvaluationLog()

    # ---- basic facts ------------------------------------------------------------------
    @property
    def n_params(self) -> int:
        return len(self.parameters)

    @property
    def n_objectives(self) -> int:
        return len(self.formulation.objective_names)

    @property
    def n_evaluations(self) -> int:
        return self.log.n_evaluations

    @property
    def x_initial(self) -> np.ndarray:
        return self.parameters.x_initial

    def reset(self) -> None:
        """Forget counted evaluations (a new run on the same problem)."""
        self.log = EvaluationLog()

    def theta(self, x: np.ndarray) -> np.ndarray:
        return self.parameters.to_physical(x)

    # ---- evaluation ---------------------------------------------------------------------
    def evaluate(self, X: np.ndarray, *, record: bool = True) -> Evaluations:
        """Evaluate points X (n, k) in normalized coordinates (clipped to [0, 1])."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        if X.shape[1] != self.n_params:
            raise ValueError(f"points have {X.shape[1]} coordinates, problem has {self.n_params} parameters")
        X = np.clip(X, 0.0, 1.0)
        theta = self.parameters.to_physical(X)
        thetas = [self.parameters.as_dict(t) for t in theta]
        results = self.runner(self.model, thetas) if self.runner is not None else modal_many(self.model, thetas)
        n, r = len(thetas), self.n_residuals
        residuals = np.empty((n, r))
        ok = np.ones(n, dtype=bool)
        reasons: list[str | None] = [None] * n
        details: list[str] = [""] * n
        correlations: list[ModeCorrelation | None] = [None] * n
        penalties = penalty_residuals(theta, X, self.parameters, self.spec)
        fail_value = np.sqrt(self.spec.failure_penalty / r)
        batch = self._batch_residuals(results)
        for i, res in enumerate(results):
            if isinstance(res, ModalResult):
                try:
                    if batch is not None:
                        modal_r, corr = batch[0][i], batch[1][i]
                    else:
                        modal_r, corr = self.formulation.residuals(res, self.measured, self.spec)
                    residuals[i, : self.n_modal_residuals] = modal_r
                    residuals[i, self.n_modal_residuals :] = penalties[i]
                    correlations[i] = corr
                    if not np.all(np.isfinite(residuals[i])):
                        raise ModelEvaluationError("non_finite_residual", str(residuals[i]))
                    continue
                except ModelEvaluationError as exc:
                    res = exc
                except (ValueError, KeyError, IndexError) as exc:
                    res = ModelEvaluationError("correlation_failed", f"{type(exc).__name__}: {exc}")
            if not isinstance(res, ModelEvaluationError):
                res = ModelEvaluationError("model_error", repr(res))
            ok[i] = False
            reasons[i] = res.reason
            details[i] = res.detail
            residuals[i] = fail_value
            log.debug("evaluation failed at %s: %s", thetas[i], res)
        objective = np.sum(residuals**2, axis=1)
        if record:
            self.log.record(X, objective, reasons, details)
        return Evaluations(objective, residuals, ok, reasons, correlations)

    def _batch_residuals(self, results: list):
        """Vectorized residuals when every point succeeded with the same modes, else None."""
        fn = self.formulation.batch_residuals
        if fn is None or len(results) < 2 or not all(isinstance(r, ModalResult) for r in results):
            return None
        n_modes = {r.n_modes for r in results}
        if len(n_modes) != 1:
            return None
        use_shapes = self.spec.use_shapes and self.measured.has_shapes
        try:
            shapes = np.stack([r.at(self.measured.dofs) for r in results]) if use_shapes else None
        except KeyError:
            return None
        if use_shapes and np.any(np.sum(shapes**2, axis=1) == 0):
            return None  # the per-point path reports the zero-norm mode
        freqs = np.stack([r.frequencies_hz for r in results])
        return fn(freqs, shapes, self.measured, self.spec)

    def objective(self, X: np.ndarray) -> np.ndarray:
        """Scalar objective Pi for each row of X (n, k) -> (n,)."""
        return self.evaluate(X).objective

    def objective1(self, x: np.ndarray) -> float:
        """Scalar objective of one point x (k,)."""
        return float(self.evaluate(np.asarray(x)[None, :]).objective[0])

    def residuals(self, x: np.ndarray) -> np.ndarray:
        """Residual vector of one point; sum of squares equals Pi."""
        return self.evaluate(np.asarray(x)[None, :]).residuals[0]

    def objectives(self, X: np.ndarray) -> np.ndarray:
        """Objective vector for each row of X -> (n, n_objectives), penalties added to each."""
        ev = self.evaluate(X)
        F = self.formulation.split(ev.residuals[:, : self.n_modal_residuals], self.measured, self.spec)
        extra = np.sum(ev.residuals[:, self.n_modal_residuals :] ** 2, axis=1)
        F = F + extra[:, None]
        F[~ev.ok] = self.spec.failure_penalty
        return F

    # ---- reporting ------------------------------------------------------------------------
    def correlation_at(self, theta: np.ndarray) -> ModeCorrelation:
        """Correlation at a physical point (not counted as an optimizer evaluation)."""
        x = self.parameters.to_normalized(np.asarray(theta, float))
        ev = self.evaluate(x[None, :], record=False)
        if not ev.ok[0]:
            raise ModelEvaluationError(ev.reasons[0] or "failed", f"at theta={theta}")
        return ev.correlations[0]

    def mode_table(self, theta: np.ndarray) -> pd.DataFrame:
        """One row per measured mode at physical point theta: f, error %, MAC, matched."""
        return correlation_table(self.correlation_at(theta), self.measured)
