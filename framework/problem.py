"""The updating problem: normalized x in [0, 1]^k -> physical theta -> model -> objective.

An :class:`UpdatingProblem` is a frozen description (model, measured modes, parameters,
objective spec) with one pure function, ``evaluate(X, runner=None) -> Evaluations``,
that returns every view of one definition for n points: the scalar objective Pi (n,)
(PSO/GA/annealing), the residual vectors (n, r) whose sums of squares are Pi (least
squares / the sensitivity method) and the objective vectors (n, n_obj) (NSGA-II). A
failed evaluation becomes the documented penalty (see :mod:`framework.objectives`) and
carries its reason. Nothing is counted or remembered here: the evaluation count, the best
point, the history, the failures and the budget of one optimizer run belong to the
per-run :class:`~framework.evaluator.Evaluator` that ``run_optimizer`` creates.

The model is evaluated through a *runner* ``runner(model, thetas) -> list`` (serial by
default; process pools and Dask in :mod:`framework.parallel`), passed per call: how the
model is evaluated is an execution detail, not part of the problem, which stays a plain,
picklable description.

Problem transforms (two damage states at once, :func:`framework.damage.two_state`; the
SNT derated objective, :func:`framework.optimizers.niching.derated`) follow the same
protocol: ``parameters``, ``n_params``, ``n_objectives``, ``x_initial``,
``evaluations_per_point`` (model evaluations per point) and ``evaluate(X, runner=None)``.
"""

from __future__ import annotations

import logging
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
    use_shape_term,
)
from framework.parameters import ParameterSet

log = logging.getLogger(__name__)

Runner = Callable[[StructuralModel, Sequence[dict]], list]


@dataclass(frozen=True)
class Evaluations:
    """Every view of n evaluated points.

    objective (n,): Pi = sum of squared residuals; residuals (n, r); objectives
    (n, n_obj): the split view (penalty terms added to each objective, failed rows =
    failure_penalty); ok (n,): the evaluation succeeded; reasons / details: failure
    category and message per point (None / "" when ok); correlations: per point mode
    pairing (None when failed). ``source``: for a transform that changes the objective
    (the SNT derating), the evaluations of the untransformed problem, else None.
    """

    objective: np.ndarray
    residuals: np.ndarray
    objectives: np.ndarray
    ok: np.ndarray
    reasons: list[str | None]
    details: list[str]
    correlations: list
    source: Evaluations | None = None

    def __len__(self) -> int:
        return len(self.objective)


def as_points(X, n_params: int) -> np.ndarray:
    """X as an (n, k) float array clipped to [0, 1]; a wrong width or a NaN raises ValueError."""
    X = np.atleast_2d(np.asarray(X, dtype=float))
    if X.ndim != 2 or X.shape[1] != n_params:
        raise ValueError(f"points have {X.shape[-1]} coordinates, problem has {n_params} parameters")
    if np.isnan(X).any():
        raise ValueError("points contain NaN (a failed run's parameters are NaN: there is nothing to evaluate)")
    return np.clip(X, 0.0, 1.0)


class UpdatingProblem:
    """Model updating of ``model`` to ``measured`` over ``parameters`` (default: all of the model's).

    Immutable after construction; ``evaluate`` is pure (the same X gives the same
    Evaluations), so one problem can serve any number of runs, in any order or process.
    """

    evaluations_per_point = 1

    def __init__(
        self,
        model: StructuralModel,
        measured: MeasuredModes,
        parameters: ParameterSet | None = None,
        objective: ObjectiveSpec | None = None,
        name: str = "",
    ):
        _check_type("model", model, StructuralModel, "a structural model (parameters, dofs, modal(theta))")
        _check_type("measured", measured, MeasuredModes, "MeasuredModes (see framework.measurements.load)")
        _check_type("parameters", parameters, (ParameterSet, type(None)), "a ParameterSet or None")
        _check_type("objective", objective, (ObjectiveSpec, type(None)), "an ObjectiveSpec or None")
        _check_type("name", name, str, "a string")
        self.model = model
        self.measured = measured
        self.parameters = parameters if parameters is not None else model.parameters
        self.spec = objective if objective is not None else ObjectiveSpec()
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
        weighted = self.spec.formulation in ("spec", "reference")  # formulations that use alpha and beta
        if weighted and self.spec.alpha == 0 and not use_shape_term(measured, self.spec):
            raise InputError(
                f"objective.alpha is 0 and there is no MAC term ({measured.source} has no shapes or "
                "use_shapes is false): the objective would be identically 0"
            )
        self.n_modal_residuals = self.formulation.n_residuals(measured, self.spec)
        self.n_residuals = self.n_modal_residuals + n_penalty_residuals(self.parameters, self.spec)
        self._frozen = True

    def __setattr__(self, name, value):
        if getattr(self, "_frozen", False):
            raise AttributeError(f"UpdatingProblem is immutable: build a new one instead of setting {name!r}")
        object.__setattr__(self, name, value)

    # ---- basic facts ------------------------------------------------------------------
    @property
    def n_params(self) -> int:
        return len(self.parameters)

    @property
    def n_objectives(self) -> int:
        return len(self.formulation.objective_names)

    @property
    def x_initial(self) -> np.ndarray:
        return self.parameters.x_initial

    def theta(self, x: np.ndarray) -> np.ndarray:
        return self.parameters.to_physical(x)

    # ---- evaluation ---------------------------------------------------------------------
    def evaluate(self, X: np.ndarray, runner: Runner | None = None) -> Evaluations:
        """Evaluate points X (n, k) in normalized coordinates (clipped to [0, 1]); pure."""
        X = as_points(X, self.n_params)
        theta = self.parameters.to_physical(X)
        thetas = [self.parameters.as_dict(t) for t in theta]
        results = runner(self.model, thetas) if runner is not None else modal_many(self.model, thetas)
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
            correlations[i] = None
            log.debug("evaluation failed at %s: %s", thetas[i], res)
        objective = np.sum(residuals**2, axis=1)
        F = self.formulation.split(residuals[:, : self.n_modal_residuals], self.measured, self.spec)
        F = F + np.sum(residuals[:, self.n_modal_residuals :] ** 2, axis=1)[:, None]
        F[~ok] = self.spec.failure_penalty
        return Evaluations(objective, residuals, F, ok, reasons, details, correlations)

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

    # ---- uncounted conveniences (a run counts through its Evaluator) ----------------------
    def objective(self, X: np.ndarray, runner: Runner | None = None) -> np.ndarray:
        """Scalar objective Pi for each row of X (n, k) -> (n,)."""
        return self.evaluate(X, runner).objective

    def objective1(self, x: np.ndarray, runner: Runner | None = None) -> float:
        """Scalar objective of one point x (k,)."""
        return float(self.evaluate(np.asarray(x, float)[None, :], runner).objective[0])

    def residuals(self, x: np.ndarray, runner: Runner | None = None) -> np.ndarray:
        """Residual vector of one point; sum of squares equals Pi."""
        return self.evaluate(np.asarray(x, float)[None, :], runner).residuals[0]

    def objectives(self, X: np.ndarray, runner: Runner | None = None) -> np.ndarray:
        """Objective vector for each row of X -> (n, n_objectives), penalties added to each."""
        return self.evaluate(X, runner).objectives

    # ---- reporting ------------------------------------------------------------------------
    def correlation_at(self, theta: np.ndarray, runner: Runner | None = None) -> ModeCorrelation:
        """Mode pairing at a physical point theta; a failed evaluation raises ModelEvaluationError."""
        x = self.parameters.to_normalized(np.asarray(theta, float))
        ev = self.evaluate(x[None, :], runner)
        if not ev.ok[0]:
            raise ModelEvaluationError(ev.reasons[0] or "failed", f"at theta={theta}: {ev.details[0]}")
        return ev.correlations[0]

    def mode_table(self, theta: np.ndarray, runner: Runner | None = None) -> pd.DataFrame:
        """One row per measured mode at physical point theta: f, error %, MAC, matched."""
        return correlation_table(self.correlation_at(theta, runner), self.measured)


def _check_type(argument: str, value, kind, expected: str) -> None:
    if not isinstance(value, kind) or (kind is StructuralModel and isinstance(value, (dict, str))):
        raise InputError(f"UpdatingProblem: argument {argument!r} must be {expected}, got {type(value).__name__}")
