"""Global-local hybrid: a global search hands its best distinct points to the sensitivity method.

One run has two phases within the run's evaluation budget ``max_evaluations``:

1. **Global phase**: ``global.algorithm`` (pso, ga, annealing, snt, or ``screening``, a
   quasi-random sample, :mod:`framework.optimizers.screening`) with ``global.settings``, on
   at most ``global.max_evaluations`` model evaluations (which must leave some of the run's
   budget for the second phase), under the run's termination rule. Every point it evaluates
   is recorded with its (raw, underated) objective.
2. **Local phase**: the sensitivity method (:mod:`framework.optimizers.sm`, ``local.settings``,
   e.g. its ``diff_step``, or its Jacobian choice where available) from each of the
   ``n_candidates`` best *distinct* points of the global phase, best first. Candidate c is
   given the evaluations left divided by the candidates still to polish (unused evaluations
   roll over), at most ``max_evaluations_per_candidate``, under the run's termination rule.
3. **Refinement** (``refine`` = r > 0, ours): SM again from the end points of the r best
   polished candidates (best first), each with the evaluations left divided by the
   refinements still to run (unused evaluations roll over; none below k + 2). A short
   first polish of many candidates sorts the basins, the refinement spends the rest of the
   budget where it pays (SM converges slowly near a minimum with many parameters on their
   bounds, e.g. the footbridge). The first polish then shares the evaluations left divided
   by the candidates still to polish plus one. Recorded as candidates n_candidates + 1, ...
   with ``refines`` naming the candidate continued.

Distinct candidates: sorted by objective, a point is taken if its normalized distance to
every point already taken is larger than ``min_distance``,

    d(x, y) = ||x - y||_2 / sqrt(k)        (x, y in the normalized box [0, 1]^k),

i.e. the root-mean-square difference of the parameters as fractions of their ranges (0.1:
on average 10 % of each range apart). Fewer candidates are polished when fewer distinct
points exist. The run's result is the best point of both phases (a polished point is never
worse than its start, which SM evaluates first).

Reported (``extra``; the updating kind writes one row per key): ``global`` (algorithm,
status, iterations, evaluations, best objective and point of the global phase, and the
global algorithm's own facts, e.g. SNT's minima),
``candidate_1``, ... (start point, global objective, polished objective and point,
evaluations, iterations, SM status, distance to the best candidate), ``condition_number`` of
the polish that gave the result, and ``run_columns`` (``global_objective``,
``global_evaluations``, ``local_evaluations``, ``n_polished``, ``best_candidate``), which the
updating kind adds to the runs table. Status: that of the polish that gave the result, or
"budget" if no candidate could be polished.
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from pydantic import ConfigDict, Field, SerializeAsAny, ValidationInfo, field_serializer, field_validator

from framework.core.errors import InputError
from framework.core.status import Status
from framework.optimizers import annealing, ga, niching, pso, screening, sm
from framework.optimizers.base import Budget, BudgetExhausted, Optimizer, Outcome, Settings
from framework.updating.evaluator import Evaluator

#: the methods of the global phase
GLOBAL_ALGORITHMS: dict[str, Optimizer] = {o.name: o for o in (
    pso.OPTIMIZER, ga.OPTIMIZER, annealing.OPTIMIZER, niching.OPTIMIZER, screening.OPTIMIZER,
)}

#: SM settings that the hybrid sets itself (the start of each polish)
_START_KEYS = ("start", "start_factor", "x0")


def local_settings(v: Any, where: str, set_by: str) -> sm.SMSettings:
    """SM settings of the polishing runs (typed, strict as in a config), without a start of
    their own: ``set_by`` says who sets it."""
    given = [k for k in _START_KEYS if isinstance(v, dict) and k in v]
    if given:
        raise ValueError(f"{where}: {given} are set by {set_by}")
    return sm.OPTIMIZER.validate(v, f"{where} (sm)")


def without_start(settings: sm.SMSettings, handler) -> dict:
    """The SM settings as written into a task (and config.yaml): without the start keys."""
    return {k: v for k, v in handler(settings).items() if k not in _START_KEYS}


class GlobalPhase(Settings):
    algorithm: Literal["pso", "ga", "annealing", "snt", "screening"]
    settings: SerializeAsAny[Settings] = Field(default_factory=dict, validate_default=True)
    max_evaluations: int = Field(gt=0)

    @field_validator("settings", mode="before")
    @classmethod
    def _settings(cls, v, info: ValidationInfo):
        name = info.data.get("algorithm")
        if name is None:
            return v
        return GLOBAL_ALGORITHMS[name].validate(v, f"global.settings ({name})")


class LocalPhase(Settings):
    algorithm: Literal["sm"] = "sm"
    settings: sm.SMSettings = Field(default_factory=dict, validate_default=True)

    @field_validator("settings", mode="before")
    @classmethod
    def _settings(cls, v):
        return local_settings(v, "local.settings", "the hybrid (each polish starts at a candidate)")

    @field_serializer("settings", mode="wrap")
    def _dump(self, settings, handler):
        return without_start(settings, handler)


class HybridSettings(Settings):
    """``global`` (a Python keyword, hence the field name ``global_phase``), ``local``,
    ``n_candidates`` and ``min_distance`` (module docstring)."""

    model_config = ConfigDict(extra="forbid", frozen=True, validate_by_name=True, validate_by_alias=True,
                              serialize_by_alias=True)

    global_phase: GlobalPhase = Field(alias="global")
    local: LocalPhase = Field(default_factory=LocalPhase)
    n_candidates: int = Field(3, ge=1)
    min_distance: float = Field(0.1, ge=0, le=1)
    max_evaluations_per_candidate: int | None = Field(None, gt=0)
    refine: int = Field(0, ge=0)


class _Recorder(Evaluator):
    """Child evaluator of the global phase that keeps every evaluated point and its raw objective."""

    def __init__(self, problem, max_evaluations, parent):
        super().__init__(problem, max_evaluations, parent=parent)
        self.points: list[np.ndarray] = []

    def _record(self, X, ev) -> None:
        super()._record(X, ev)
        self.points.append(np.array(X, dtype=float))

    def evaluated(self) -> tuple[np.ndarray, np.ndarray]:
        """Points (n, k) and objectives (n,), NaN where the evaluation failed."""
        if not self.points:
            return np.zeros((0, self.n_params)), np.zeros(0)
        return np.vstack(self.points), np.concatenate(self._values)


def distinct_best(X: np.ndarray, values: np.ndarray, n: int, min_distance: float) -> list[int]:
    """Indices of up to n best points (lowest finite value first) pairwise farther apart than
    ``min_distance`` in the normalized distance ||x - y|| / sqrt(k); ties keep the earlier point."""
    k = X.shape[1] if X.ndim == 2 else 1
    order = np.argsort(np.where(np.isfinite(values), values, np.inf), kind="stable")
    order = order[np.isfinite(values[order])]
    free = np.ones(len(X), dtype=bool)
    chosen: list[int] = []
    for i in order:
        if len(chosen) == n:
            break
        if not free[i]:
            continue
        chosen.append(int(i))
        free &= np.linalg.norm(X - X[i], axis=1) / np.sqrt(k) > min_distance
    return chosen


def _refine(evaluator, seed: int, budget: Budget, s: HybridSettings, best: dict, number: int, share: int) -> dict:
    """SM again from a polished point with ``share`` evaluations (``refine``); its record is
    numbered after the candidates, with ``refines`` naming the candidate it continues."""
    x0 = np.asarray(best["x_polished"], dtype=float)
    child = Evaluator(evaluator.problem, share, parent=evaluator)
    out = sm.run(child, seed, budget.model_copy(update={"max_evaluations": share}), polish_from(s.local.settings, x0))
    params = evaluator.parameters
    return {
        "candidate": number,
        "refines": best["candidate"], "x_start": x0.tolist(), "theta_start": params.to_physical(x0).tolist(),
        "global_objective": best["global_objective"], "distance_to_first": best["distance_to_first"],
        "polished_objective": float(child.best_objective) if child.has_success else None,
        "x_polished": None if child.best_x is None else child.best_x.tolist(),
        "theta_polished": None if child.best_x is None else params.to_physical(child.best_x).tolist(),
        "n_evaluations": child.n_evaluations, "n_iterations": out.n_iterations, "status": out.status,
        "_extra": out.extra,
    }


def polish_from(settings: sm.SMSettings, x0: np.ndarray) -> sm.SMSettings:
    """The local settings with the start ``x0`` (normalized)."""
    return settings.model_copy(update={"x0": np.asarray(x0, float).tolist()})


def run(evaluator, seed: int, budget: Budget, s: HybridSettings) -> Outcome:
    g = s.global_phase
    if g.max_evaluations >= budget.max_evaluations:
        raise InputError(f"hybrid: global.max_evaluations ({g.max_evaluations}) must be below the run's "
                         f"max_evaluations ({budget.max_evaluations}) to leave evaluations for the local phase")
    problem = evaluator.problem
    params = evaluator.parameters

    # ---- global phase
    recorder = _Recorder(problem, g.max_evaluations, evaluator)
    try:
        global_out = GLOBAL_ALGORITHMS[g.algorithm].run(
            recorder, seed, budget.model_copy(update={"max_evaluations": g.max_evaluations}), g.settings)
        global_status, global_iterations, global_extra = global_out.status, global_out.n_iterations, global_out.extra
    except BudgetExhausted:
        global_status, global_iterations, global_extra = Status.BUDGET, 0, {}
    X, values = recorder.evaluated()
    picks = distinct_best(X, values, s.n_candidates, s.min_distance)
    global_record = {
        "algorithm": g.algorithm, "status": global_status, "n_iterations": int(global_iterations),
        "n_evaluations": recorder.n_evaluations,
        "objective": float(recorder.best_objective) if recorder.has_success else float("nan"),
        "x_best": None if recorder.best_x is None else recorder.best_x.tolist(),
        "n_points": int(len(X)), "n_failed": recorder.n_failed, "extra": global_extra,
    }

    # ---- local phase
    candidates: list[dict] = []
    iterations = int(global_iterations)
    best_c, best_value, best_extra = None, np.inf, {}
    for c, i in enumerate(picks):
        x0 = X[i]
        record = {"candidate": c + 1, "x_start": x0.tolist(), "theta_start": params.to_physical(x0).tolist(),
                  "global_objective": float(values[i]),
                  "distance_to_first": float(np.linalg.norm(x0 - X[picks[0]]) / np.sqrt(len(x0)))}
        share = int(evaluator.remaining // (len(picks) - c + (1 if s.refine else 0)))
        if s.max_evaluations_per_candidate is not None:
            share = min(share, s.max_evaluations_per_candidate)
        if share < evaluator.cost:
            candidates.append({**record, "status": "not_run", "n_evaluations": 0, "polished_objective": None})
            continue
        child = Evaluator(problem, share, parent=evaluator)
        out = sm.run(child, seed, budget.model_copy(update={"max_evaluations": share}),
                     polish_from(s.local.settings, x0))
        iterations += out.n_iterations
        polished = float(child.best_objective) if child.has_success else None
        record.update({
            "polished_objective": polished,
            "x_polished": None if child.best_x is None else child.best_x.tolist(),
            "theta_polished": None if child.best_x is None else params.to_physical(child.best_x).tolist(),
            "n_evaluations": child.n_evaluations, "n_iterations": out.n_iterations, "status": out.status,
        })
        candidates.append(record)
        if polished is not None and polished < best_value:
            best_c, best_value, best_extra, best_status = c + 1, polished, out.extra, out.status

    polished = [r for r in candidates if r.get("polished_objective") is not None]
    polished.sort(key=lambda r: r["polished_objective"])
    chosen = polished[: s.refine]
    for j, start in enumerate(chosen):
        share = int(evaluator.remaining // (len(chosen) - j))
        if share < evaluator.n_params + 2:  # not even one forward-difference iteration
            break
        record = _refine(evaluator, seed, budget, s, start, len(candidates) + 1, share)
        candidates.append(record)
        iterations += record["n_iterations"]
        extra_j = record.pop("_extra")
        if record["polished_objective"] is not None and record["polished_objective"] < best_value:
            best_c, best_value, best_extra, best_status = record["candidate"], record["polished_objective"], extra_j, \
                record["status"]
    local_evaluations = sum(r["n_evaluations"] for r in candidates)
    status = best_status if best_c is not None else Status.BUDGET
    extra: dict[str, Any] = {"global": global_record}
    extra.update({f"candidate_{r['candidate']}": r for r in candidates})
    if "condition_number" in best_extra:
        extra["condition_number"] = best_extra["condition_number"]
    extra["run_columns"] = {
        "global_objective": global_record["objective"], "global_evaluations": recorder.n_evaluations,
        "local_evaluations": local_evaluations, "n_polished": sum(r["status"] != "not_run" for r in candidates),
        "best_candidate": best_c if best_c is not None else 0,
    }
    message = (f"global {g.algorithm} ({global_status}, {recorder.n_evaluations} evaluations, best "
               f"{global_record['objective']:.4g}); {extra['run_columns']['n_polished']} of {len(picks)} "
               f"candidate(s) polished by sm" + (f", best from candidate {best_c}" if best_c else ""))
    return Outcome(status, iterations, message=message, extra=extra)


OPTIMIZER = Optimizer("hybrid", HybridSettings, run)
