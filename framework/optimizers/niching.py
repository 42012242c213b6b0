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
"""

from __future__ import annotations

import numpy as np
from pydantic import Field

from framework.optimizers import pso
from framework.optimizers.base import Budget, OptimizerResult, Settings, Timer, make_result


class SNTSettings(Settings):
    n_minima: int = Field(4, ge=1)
    niche_radius: float | None = Field(None, gt=0)
    derating_m: float = Field(0.1, gt=0, lt=1)
    boundary_tolerance: float = Field(0.01, ge=0)
    pso: dict = Field(default_factory=dict)


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


class DeratedProblem:
    """View of a problem whose objective is derated around given minima (shares the log)."""

    def __init__(self, problem, minima: list[np.ndarray], r: float, m: float):
        self.problem, self.minima, self.r, self.m = problem, list(minima), r, m
        self.parameters = problem.parameters
        self.n_params = problem.n_params
        self.x_initial = problem.x_initial
        self.log = _SubLog(problem.log)

    def objective(self, X: np.ndarray) -> np.ndarray:
        X = np.atleast_2d(X)
        raw = self.problem.objective(X)
        derated = (1.0 + raw) / derating(np.clip(X, 0, 1), self.minima, self.r, self.m) - 1.0
        self.log.record(X, derated)
        return derated


class _SubLog:
    """Best derated point of one niche search; counts through the shared problem log."""

    def __init__(self, parent):
        self.parent = parent
        self.best_x = None
        self.best_objective = np.inf
        self.n_failed = 0

    @property
    def n_evaluations(self) -> int:
        return self.parent.n_evaluations

    def record(self, X, values) -> None:
        i = int(np.argmin(values))
        if values[i] < self.best_objective:
            self.best_objective, self.best_x = float(values[i]), np.array(X[i])

    def best_so_far(self):
        return self.parent.best_so_far()

    def failure_summary(self) -> str:
        return self.parent.failure_summary()


def run(problem, seed: int, budget: Budget, **settings) -> OptimizerResult:
    s = SNTSettings(**settings)
    r = s.niche_radius or niche_radius(problem.n_params, s.n_minima)
    minima: list[np.ndarray] = []
    records = []
    iterations = 0
    with Timer() as timer:
        for n in range(s.n_minima):
            view = DeratedProblem(problem, minima, r, s.derating_m)
            used = problem.log.n_evaluations
            sub_budget = budget.model_copy(update={"max_evaluations": used + budget.max_evaluations})
            sub = pso.run(view, seed + 1000 * n, sub_budget, **s.pso)
            iterations += sub.n_iterations
            x = np.clip(view.log.best_x, 0, 1)
            raw = problem.objective1(x)
            derated = (1.0 + raw) / float(derating(x[None, :], minima, r, s.derating_m)[0]) - 1.0
            distances = [float(np.linalg.norm(x - m_)) for m_ in minima]
            # a search pushed out of a niche often stops right on its edge (d = r), where the
            # derating is 1 again: raw == derated, yet the point is an artefact of the radius
            on_boundary = bool(any(abs(d - r) <= s.boundary_tolerance * r for d in distances))
            records.append(
                {
                    "minimum": n + 1,
                    "x": x.tolist(),
                    "theta": problem.parameters.to_physical(x).tolist(),
                    "raw_objective": raw,
                    "derated_objective": derated,
                    "inside_niche": bool(not np.isclose(raw, derated, rtol=1e-9, atol=1e-15)),
                "on_niche_boundary": on_boundary,
                "artefact": bool(not np.isclose(raw, derated, rtol=1e-9, atol=1e-15)) or on_boundary,
                    "distance_to_previous": distances,
                    "n_evaluations": problem.log.n_evaluations - used,
                }
            )
            minima.append(x)
    best = min(records, key=lambda rec: rec["raw_objective"])
    return make_result(
        "snt",
        problem,
        seed,
        timer.elapsed,
        "completed",
        iterations,
        extra={"minima": records, "niche_radius": r, "derating_m": s.derating_m},
        x_best=np.array(best["x"]),
        objective=best["raw_objective"],
    )
