"""Sequential niche technique (SNT) with PSO: find several minima one after another.

After minimum s_n is found, the next search runs on a derated objective that is raised
near every minimum found so far. The source derates a maximised fitness F by

    G(x, s) = exp(log(m) (r - d) / r)  if d < r  else 1,      m < 1,

d the distance from x to s in normalized parameter space and r the niche radius
r = sqrt(k) / (2 p^(1/k)) (k parameters, p expected minima). For our minimised,
non-negative Pi we derate the fitness F = 1 / (1 + Pi) and minimise the equivalent

    Pi_n+1(x) = (1 + Pi(x)) / prod_j G(x, s_j) - 1,

which equals Pi away from all minima and rises steeply inside a niche (to (1+Pi)/m - 1 at
its centre). Each minimum is reported with its raw Pi and its derated value at the time
it was found. Two kinds of minima are artefacts of the niche radius and flagged so: one
whose raw and derated values differ lies inside an earlier niche (``inside_niche``), and one
that sits on the edge of an earlier niche, |d - r| <= 1 % of r (``on_niche_boundary``),
where the derating is back to 1 but the search was only stopped by the niche wall.

Budget: ``max_evaluations`` is the total of the whole SNT run. Niche search n (of p) is
given the evaluations left divided by the niches still to find, so unused evaluations
roll over to the later searches; the stall and target rules apply to each niche search
(on its derated objective). The raw Pi of each minimum is recomputed for the report and
not counted (like a mode table).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from pydantic import Field, field_serializer

from framework.core.status import Status
from framework.optimizers import pso
from framework.optimizers.base import Budget, Optimizer, Outcome, Settings
from framework.optimizers.pso import PSOSettings
from framework.updating.problem import Evaluations


class SNTSettings(Settings):
    n_minima: int = Field(4, ge=1)
    niche_radius: float | None = Field(None, gt=0)
    derating_m: float = Field(0.1, gt=0, lt=1)
    boundary_tolerance: float = Field(0.01, ge=0)
    #: the settings of each niche's PSO run
    pso: PSOSettings = Field(default_factory=PSOSettings)

    @field_serializer("pso")
    def _as_given(self, settings: PSOSettings) -> dict:
        """Only the PSO settings given (as a run's identity has always held them)."""
        return settings.model_dump(mode="json", exclude_unset=True)


def niche_radius(k: int, p: int) -> float:
    """r = sqrt(k) / (2 p^(1/k)); k = 6, p = 4 gives 0.97."""
    return float(np.sqrt(k) / (2.0 * p ** (1.0 / k)))


def derating(X: np.ndarray, minima: list[np.ndarray], r: float, m: float) -> np.ndarray:
    """prod_j G(x, s_j) for each row of X."""
    G = np.ones(len(X))
    for s in minima:
        d = np.linalg.norm(X - s, axis=1)
        G *= np.where(d < r, np.exp(np.log(m) * (r - d) / r), 1.0)
    return G


@dataclass(frozen=True)
class Derated:
    """Transform of a problem: Pi_n+1(x) = (1 + Pi(x)) / prod_j G(x, s_j) - 1 around ``minima``.

    Same protocol as the problem (``evaluate(X, runner)``); its Evaluations carry the
    derated objective (residuals and objective vectors are the problem's own) and, as
    ``source``, the problem's evaluations, so a run's evaluator records the raw values.
    A failed point keeps the problem's failure penalty.
    """

    problem: object
    minima: tuple
    radius: float
    m: float

    @property
    def parameters(self):
        return self.problem.parameters

    @property
    def n_params(self) -> int:
        return self.problem.n_params

    @property
    def n_objectives(self) -> int:
        return self.problem.n_objectives

    @property
    def x_initial(self) -> np.ndarray:
        return self.problem.x_initial

    @property
    def evaluations_per_point(self) -> int:
        return getattr(self.problem, "evaluations_per_point", 1)

    def value(self, X: np.ndarray, raw: np.ndarray) -> np.ndarray:
        """Derated objective of points X (n, k) whose raw objective is ``raw``."""
        return (1.0 + raw) / derating(np.clip(X, 0, 1), list(self.minima), self.radius, self.m) - 1.0

    def evaluate(self, X: np.ndarray, runner=None) -> Evaluations:
        ev = self.problem.evaluate(X, runner)
        X = np.clip(np.atleast_2d(np.asarray(X, float)), 0.0, 1.0)
        derated = np.where(ev.ok, self.value(X, ev.objective), ev.objective)
        return replace(ev, objective=derated, source=ev)


def derated(problem, minima, radius: float, m: float) -> Derated:
    """``problem`` derated around the points ``minima`` (normalized) with niche radius and m."""
    return Derated(problem, tuple(np.asarray(s_, float) for s_ in minima), float(radius), float(m))


def run(evaluator, seed: int, budget: Budget, s: SNTSettings) -> Outcome:
    problem = evaluator.problem
    r = s.niche_radius or niche_radius(evaluator.n_params, s.n_minima)
    minima: list[np.ndarray] = []
    records = []
    iterations = 0
    for n in range(s.n_minima):
        share = int(evaluator.remaining // (s.n_minima - n))
        if share <= 0:
            break
        view = derated(problem, minima, r, s.derating_m)
        sub_evaluator = evaluator.child(view, share)
        sub_budget = budget.model_copy(update={"max_evaluations": share})
        sub = pso.run(sub_evaluator, seed + 1000 * n, sub_budget, s.pso)
        iterations += sub.n_iterations
        if sub_evaluator.best_x is None:  # no successful evaluation in this niche search
            records.append({"minimum": n + 1, "failed": True, "n_evaluations": sub_evaluator.n_evaluations,
                            "status": sub.status})  # fmt: skip
            continue
        x = np.clip(sub_evaluator.best_x, 0, 1)
        raw = float(problem.evaluate(x[None, :], evaluator.runner).objective[0])
        derated_value = float(view.value(x[None, :], np.array([raw]))[0])
        distances = [float(np.linalg.norm(x - m_)) for m_ in minima]
        # a search pushed out of a niche often stops right on its edge (d = r), where the
        # derating is 1 again: raw == derated, yet the point is an artefact of the radius
        on_boundary = bool(any(abs(d - r) <= s.boundary_tolerance * r for d in distances))
        inside = bool(not np.isclose(raw, derated_value, rtol=1e-9, atol=1e-15))
        records.append(
            {
                "minimum": n + 1,
                "x": x.tolist(),
                "theta": problem.parameters.to_physical(x).tolist(),
                "raw_objective": raw,
                "derated_objective": derated_value,
                "inside_niche": inside,
                "on_niche_boundary": on_boundary,
                "artefact": inside or on_boundary,
                "distance_to_previous": distances,
                "n_evaluations": sub_evaluator.n_evaluations,
                "status": sub.status,
            }
        )
        minima.append(x)
    found = [rec for rec in records if not rec.get("failed")]
    best = min(found, key=lambda rec: rec["raw_objective"]) if found else None
    return Outcome(
        Status.COMPLETED if len(records) == s.n_minima else Status.BUDGET,
        iterations,
        message=f"{len(found)} of {s.n_minima} minima found",
        extra={"minima": records, "niche_radius": r, "derating_m": s.derating_m},
        x_best=np.array(best["x"]) if best else None,
        objective=best["raw_objective"] if best else None,
    )


OPTIMIZER = Optimizer("snt", SNTSettings, run)
