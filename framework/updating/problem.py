"""The updating problem: normalized x in [0, 1]^k -> physical theta -> model -> objective.

An :class:`UpdatingProblem` is a frozen description (model, measured modes, parameters,
objective spec) with one pure function, ``evaluate(X, runner=None) -> Evaluations``,
that returns every view of one definition for n points: the scalar objective Pi (n,)
(PSO/GA/annealing), the residual vectors (n, r) whose sums of squares are Pi (least
squares / the sensitivity method) and the objective vectors (n, n_obj) (NSGA-II). A
failed evaluation becomes the documented penalty (see :mod:`framework.updating.objectives`) and
carries its reason. Nothing is counted or remembered here: the evaluation count, the best
point, the history, the failures and the budget of one optimizer run belong to the
per-run :class:`~framework.updating.evaluator.Evaluator` that ``run_optimizer`` creates.

The model is evaluated through a *runner* ``runner(model, thetas) -> list`` (serial by
default; process pools and Dask in :mod:`framework.execution.parallel`), passed per call: how the
model is evaluated is an execution detail, not part of the problem, which stays a plain,
picklable description.

Vectorized models: on the in-process path (runner None or ``modal_many``) a model with
``modal_arrays`` (:mod:`framework.models.arrays`) solves the whole population in one call
without a Python object per point; a population's residuals are computed in one call
(``formulation.batch_residuals``) and its correlations kept as arrays
(:class:`~framework.updating.pairing.ModeCorrelations`, one ModeCorrelation built when asked). A
runner's list of ModalResult goes through the same vectorized code, so every runner gives
the same numbers.

``jacobian(x, runner=None)`` is the exact Jacobian dr/dx of the residual vector at one
point when the model provides modal derivatives (``model.modal_derivatives``, see
:mod:`framework.core.modal_derivatives`) and the formulation an exact Jacobian: the residual
derivatives with respect to theta from the eigenvalue and eigenvector derivatives of the
paired modes (pairing held fixed at the point: the residuals are piecewise smooth;
unmatched modes give zero rows), the penalty terms' derivatives, and the chain rule
dtheta/dx = upper - lower. Otherwise, or at a point with repeated or close eigenvalues
or where the derivatives fail (warned once per model), it is the forward-difference
Jacobian.

Problem transforms (two damage states at once, :func:`framework.damage.estimation.two_state`; the
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

from framework.core.errors import InputError, ModelEvaluationError
from framework.core.modal_derivatives import CloseEigenvalues
from framework.core.parameters import ParameterSet
from framework.measured.modes import MeasuredModes
from framework.models.arrays import ModalArrays, array_method
from framework.models.base import ModalResult, StructuralModel, modal_many
from framework.updating.formulations import get_formulation
from framework.updating.objectives import (
    ObjectiveSpec,
    check_constraints,
    n_penalty_residuals,
    penalty_jacobian,
    penalty_residuals,
)
from framework.updating.pairing import ModeCorrelation, ModeCorrelations, correlation_table, use_shape_term

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
    #: the model's ModalResult (or ModelEvaluationError) per point, when asked for (``keep_results``)
    results: list | None = None

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
        _check_type("measured", measured, MeasuredModes, "MeasuredModes (see framework.measured.modes.load)")
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
        if self.formulation.uses_weights and self.spec.alpha == 0 and not use_shape_term(measured, self.spec):
            raise InputError(
                f"objective.alpha is 0 and there is no MAC term ({measured.source} has no shapes or "
                "use_shapes is false): the objective would be identically 0"
            )
        if self.formulation.check_data is not None:
            self.formulation.check_data(measured, self.spec)
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
    def evaluate(self, X: np.ndarray, runner: Runner | None = None, keep_results: bool = False) -> Evaluations:
        """Evaluate points X (n, k) in normalized coordinates (clipped to [0, 1]); pure.

        keep_results: also return the model's results (``Evaluations.results``), e.g. to
        differentiate at the point without solving it again."""
        X = as_points(X, self.n_params)
        theta = self.parameters.to_physical(X)
        n, r, m = len(X), self.n_residuals, self.n_modal_residuals
        residuals = np.empty((n, r))
        residuals[:, m:] = penalty_residuals(theta, X, self.parameters, self.spec)
        modal = self._solve(theta, runner, per_point=keep_results)
        residuals[:, :m], errors, correlations = self._modal_residuals(modal)
        ok = np.ones(n, dtype=bool)
        ok[list(errors)] = False
        for i in np.flatnonzero(ok & ~np.all(np.isfinite(residuals), axis=1)):
            errors[int(i)] = ModelEvaluationError("non_finite_residual", str(residuals[i]))
        reasons: list[str | None] = [None] * n
        details: list[str] = [""] * n
        for i, exc in errors.items():
            ok[i] = False
            reasons[i], details[i] = exc.reason, exc.detail
            if log.isEnabledFor(logging.DEBUG):
                log.debug("evaluation failed at %s: %s", self.parameters.as_dict(theta[i]), exc)
        residuals[~ok] = np.sqrt(self.spec.failure_penalty / r)
        correlations = correlations.where(ok) if isinstance(correlations, ModeCorrelations) else [
            c if ok[i] else None for i, c in enumerate(correlations)]
        objective = np.sum(residuals**2, axis=1)
        F = self.formulation.split(residuals[:, :m], self.measured, self.spec)
        F = F + np.sum(residuals[:, m:] ** 2, axis=1)[:, None]
        F[~ok] = self.spec.failure_penalty
        return Evaluations(objective, residuals, F, ok, reasons, details, correlations,
                           results=list(modal) if keep_results else None)

    def _solve(self, theta: np.ndarray, runner: Runner | None, per_point: bool = False):
        """Modes of the points theta (n, k): a :class:`ModalArrays` in process for a model with
        ``modal_arrays`` (no per-point objects), else (or with ``per_point``) the runner's list
        (ModalResult or error)."""
        if not per_point and (runner is None or runner is modal_many):
            arrays = array_method(self.model)
            if arrays is not None:
                return arrays(theta, self.parameters.names)
        thetas = [self.parameters.as_dict(t) for t in theta]
        return runner(self.model, thetas) if runner is not None else modal_many(self.model, thetas)

    def _modal_residuals(self, modal):
        """Modal residuals (n, r_m), failed points {index: ModelEvaluationError} and correlations.

        A population of two or more points is done in one vectorized call when the
        formulation has ``batch_residuals`` and the solved points share their mode count
        (failed points left out); otherwise, and for points whose shapes vanish at the
        measured DOFs, point by point. Both give the same numbers to rounding (tests).
        """
        n = len(modal)
        R = np.zeros((n, self.n_modal_residuals))
        stacked = self._stack(modal) if n >= 2 and self.formulation.batch_residuals is not None else None
        if stacked is not None:
            freqs, shapes, errors = stacked
            usable = np.ones(n, dtype=bool)
            usable[list(errors)] = False
            single = np.zeros(n, dtype=bool)
            if shapes is not None:
                single = usable & np.any(np.sum(shapes**2, axis=1) == 0, axis=1)
            usable &= ~single
            rows = np.flatnonzero(usable)
            out = self.formulation.batch_residuals(freqs[rows], None if shapes is None else shapes[rows],
                                                   self.measured, self.spec) if rows.size else None
            if out is not None or not rows.size:
                full = out is not None and rows.size == n
                corr = out[1] if full else _scatter(out[1] if out is not None else None, rows, n, self.measured)
                if out is not None:
                    R[rows] = out[0]
                for i in np.flatnonzero(single):  # the per-point path names the zero-norm mode
                    res = modal.result(i) if isinstance(modal, ModalArrays) else modal[i]
                    out_i, err = self._point(res)
                    if err is not None:
                        errors[int(i)] = err
                    else:
                        R[i] = out_i[0]
                        corr.set(int(i), out_i[1])
                return R, errors, corr
        errors = {}
        correlations: list[ModeCorrelation | None] = [None] * n
        for i in range(n):
            res = modal.result(i) if isinstance(modal, ModalArrays) else modal[i]
            out_i, err = self._point(res)
            if err is not None:
                errors[i] = err
            else:
                R[i], correlations[i] = out_i
        return R, errors, correlations

    def _point(self, res):
        """((modal residuals, correlation), None) of one point's modal result, or (None, error)."""
        if isinstance(res, ModalResult):
            try:
                return self.formulation.residuals(res, self.measured, self.spec), None
            except ModelEvaluationError as exc:
                return None, exc
            except (ValueError, KeyError, IndexError) as exc:
                return None, ModelEvaluationError("correlation_failed", f"{type(exc).__name__}: {exc}")
        if isinstance(res, ModelEvaluationError):
            return None, res
        return None, ModelEvaluationError("model_error", repr(res))

    def _stack(self, modal):
        """(frequencies (n, m), shapes at the measured DOFs (n, d, m) or None, errors) of the
        solved points, or None when their mode counts differ or a measured DOF is missing."""
        use_shapes = self.spec.use_shapes and self.measured.has_shapes
        if isinstance(modal, ModalArrays):
            errors = dict(modal.errors)
            if not use_shapes:
                return modal.frequencies_hz, None, errors
            index = {d: j for j, d in enumerate(modal.dofs)}
            if any(d not in index for d in self.measured.dofs):
                return None
            return modal.frequencies_hz, modal.shapes[:, [index[d] for d in self.measured.dofs], :], errors
        solved = [i for i, res in enumerate(modal) if isinstance(res, ModalResult)]
        if not solved or len({modal[i].n_modes for i in solved}) != 1:
            return None
        errors = {i: self._point(res)[1] for i, res in enumerate(modal) if not isinstance(res, ModalResult)}
        m_a = modal[solved[0]].n_modes
        freqs = np.zeros((len(modal), m_a))
        freqs[solved] = np.stack([modal[i].frequencies_hz for i in solved])
        if not use_shapes:
            return freqs, None, errors
        try:
            at = np.stack([modal[i].at(self.measured.dofs) for i in solved])
        except KeyError:
            return None
        shapes = np.zeros((len(modal), len(self.measured.dofs), m_a))
        shapes[solved] = at
        return freqs, shapes, errors

    # ---- Jacobian --------------------------------------------------------------------------
    @property
    def has_exact_jacobian(self) -> bool:
        """True when the model provides modal derivatives and the formulation an exact Jacobian."""
        return callable(getattr(self.model, "modal_derivatives", None)) and self.formulation.jacobian is not None

    @property
    def jacobian_cost_bound(self) -> int:
        """Upper bound of an exact Jacobian's cost in eigen-solve equivalents (every measured mode
        differentiated); a forward-difference Jacobian costs n_params model evaluations."""
        if not self.has_exact_jacobian:
            return self.n_params
        cost = getattr(self.model, "derivative_cost", None)
        return int(cost(self.measured.n_modes, self.n_params)) if cost is not None else self.measured.n_modes

    def jacobian(
        self,
        x: np.ndarray,
        runner: Runner | None = None,
        result=None,
        *,
        fd_step: float = 1e-3,
        fallback: bool = True,
        scheme: str = "forward",
    ) -> Jacobian:
        """Jacobian dr/dx (r, k) of the residual vector at the normalized point x (module docstring).

        result: the model's ModalResult at x if known (else the model is evaluated here, not
        counted in ``Jacobian.cost``); fd_step: step in x of the finite differences of the
        fallback; scheme: "forward" (k difference points, backward at the upper bound) or
        "central" (2k points x -+ fd_step e_j clipped to [0, 1], one-sided at a bound:
        second-order accurate in the interior); fallback=False: return a Jacobian with J None
        and the reason instead of evaluating the difference points (the caller, e.g. a counting
        Evaluator, does it).
        """
        if scheme not in ("forward", "central"):
            raise ValueError(f"jacobian scheme must be 'forward' or 'central', got {scheme!r}")
        x = as_points(np.asarray(x, float)[None, :], self.n_params)[0]
        theta = self.parameters.to_physical(x)
        if result is None:
            ev = self.evaluate(x[None, :], runner, keep_results=True)
            result = ev.results[0]
        out, err = self._point(result)
        if err is None and not np.all(np.isfinite(out[0])):
            err = ModelEvaluationError("non_finite_residual", str(out[0]))
        if err is not None:  # a failed point: the residuals are the constant failure value
            return Jacobian(np.zeros((self.n_residuals, self.n_params)), "failed", 0, str(err))
        modal_r, corr = out
        reason = ""
        if self.has_exact_jacobian:
            try:
                J, cost = self._exact_jacobian(theta, result, corr)
                return Jacobian(J * self.parameters_span[None, :], "exact", cost)
            except CloseEigenvalues as exc:
                reason = f"close_eigenvalues: {exc}"
                _warn_once(self.name, reason)
            except (ModelEvaluationError, np.linalg.LinAlgError, RuntimeError) as exc:  # e.g. a singular system
                reason = f"derivatives_failed: {type(exc).__name__}: {exc}"
                _warn_once(self.name, reason)
        else:
            reason = "no_derivatives"
        if not fallback:
            return Jacobian(None, "fd", 0, reason)
        if scheme == "central":
            lo, hi = np.clip(x - fd_step, 0.0, 1.0), np.clip(x + fd_step, 0.0, 1.0)
            X = np.repeat(x[None, :], 2 * x.size, axis=0)
            X[0::2][np.arange(x.size), np.arange(x.size)] = lo
            X[1::2][np.arange(x.size), np.arange(x.size)] = hi
            ev = self.evaluate(X, runner)
            J = (ev.residuals[1::2] - ev.residuals[0::2]).T / np.maximum(hi - lo, 1e-12)[None, :]
            return Jacobian(J, "fd", len(X), reason, fd_evaluations=ev)
        X, h = fd_points(x, fd_step)
        ev = self.evaluate(X, runner)
        r0 = np.r_[modal_r, penalty_residuals(theta, x, self.parameters, self.spec)[0]]
        J = (ev.residuals - r0[None, :]).T / h[None, :]
        return Jacobian(J, "fd", len(X), reason, fd_evaluations=ev)

    @property
    def parameters_span(self) -> np.ndarray:
        """dtheta/dx = upper - lower per parameter."""
        return self.parameters.upper - self.parameters.lower

    def _exact_jacobian(self, theta: np.ndarray, result: ModalResult, corr) -> tuple[np.ndarray, int]:
        """dr/dtheta (r, k) from the model's modal derivatives of the paired modes, and its cost."""
        paired = np.unique(corr.analytical_index[corr.matched])
        names = self.parameters.names
        derivs = self.model.modal_derivatives(
            self.parameters.as_dict(theta), result, parameters=names, modes=paired.tolist()
        )
        J_modal = self.formulation.jacobian(result, derivs, corr, self.measured, self.spec)
        return np.vstack([J_modal, penalty_jacobian(theta, self.parameters, self.spec)]), int(derivs.cost)

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


def _scatter(corr, rows: np.ndarray, n: int, measured: MeasuredModes) -> ModeCorrelations:
    """Correlations of the points ``rows`` (a ModeCorrelations of len(rows), or None) placed in a
    population of n points; the other points have none."""
    m = measured.n_modes
    index, matched = np.full((n, m), -1), np.zeros((n, m), dtype=bool)
    f_model, eps, mac = (np.full((n, m), np.nan) for _ in range(3))
    present = np.zeros(n, dtype=bool)
    if corr is not None:
        index[rows], f_model[rows], eps[rows] = corr.analytical_index, corr.f_model_hz, corr.frequency_error
        mac[rows], matched[rows], present[rows] = corr.mac, corr.matched, True
    return ModeCorrelations(index, measured.frequencies_hz, f_model, eps, mac, matched, present)

@dataclass(frozen=True)
class Jacobian:
    """Jacobian dr/dx (r, k) in normalized coordinates at one point.

    method: "exact" (modal derivatives), "fd" (forward differences) or "failed" (the point
    failed: zero Jacobian); cost: eigen-solve equivalents of an exact Jacobian, or the number
    of difference points evaluated; reason: why not exact; fd_evaluations: the difference
    points' evaluations (a counting evaluator records them).
    """

    J: np.ndarray | None
    method: str
    cost: int
    reason: str = ""
    fd_evaluations: Evaluations | None = None


def fd_points(x: np.ndarray, step: float) -> tuple[np.ndarray, np.ndarray]:
    """Forward-difference points x + h_j e_j (backward where x_j + step > 1); returns (X (k, k), h (k,))."""
    x = np.asarray(x, float)
    h = np.where(x + step <= 1.0, step, -step)
    X = np.tile(x, (x.size, 1)) + np.diag(h)
    return X, h


_WARNED: set[str] = set()


def _warn_once(name: str, message: str) -> None:
    """Log the first finite-difference fallback of each model as a warning, later ones at debug level."""
    if name in _WARNED:
        log.debug("%s: finite-difference Jacobian (%s)", name, message)
        return
    _WARNED.add(name)
    log.warning("%s: finite-difference Jacobian at this point (%s); further fallbacks are logged at debug level",
                name, message)


def _check_type(argument: str, value, kind, expected: str) -> None:
    if not isinstance(value, kind) or (kind is StructuralModel and isinstance(value, (dict, str))):
        raise InputError(f"UpdatingProblem: argument {argument!r} must be {expected}, got {type(value).__name__}")
