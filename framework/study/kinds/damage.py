"""Run kind ``damage``: damage estimation of two damage states of the beam (SPEC 7).

One run = one procedure on one measurement draw (noise level, seed). The a-priori model is
the 10-element numpy beam (vectorized over populations); the measurements are the
20-element truth's first ``n_modes`` frequencies (noise-free) and shapes with multiplicative
noise phi (1 + a eps), a = noise_pct / 100, drawn independently per state from the run's
seed (``numpy.random.SeedSequence([seed, state index])``). Procedures and the methods each
reports (``method``; "(ours)" marks our variants, the others are the source's):

- ``single_objective``: PSO (``pso`` budget) and the sensitivity method on each of the
  intact, state-1 and state-2 data. Methods: ``soo`` (the source's procedure: the intact
  update is the baseline, damage severity = r_intact - r_state, estimated ratio
  1 - severity), ``soo+sm (ours)`` (the same with each PSO result polished by
  ``run_optimizer("sm", x0=...)``), ``pso (ours)``, ``pso+sm (ours)``, ``sm (ours)``
  (independent updates of each state against the initial model);
- ``nsga2``: NSGA-II on both damaged states at once (20 parameters, objectives
  [Pi_1, Pi_2], the point nearest the ideal point). Methods ``nsga2``, ``nsga2+sm (ours)``;
- ``tikhonov``: the L-curve over the tau grid, traced by sensitivity-method continuation
  (each tau started from the previous minimum; ours: cheap, a PSO per tau would cost 50 000
  evaluations each), corner by maximum curvature (Hansen); then PSO on
  Pi + tau ||r - 1||^2 at the corner tau. Methods ``pso_tikhonov``, ``pso_tikhonov+sm (ours)``.

Tables (each row also carries the run key and the typed columns procedure, noise_pct,
measured_mesh):

- ``runs``: one row per run: status, error, n_evaluations (model evaluations), wall_s;
- ``states``: run x method x state: objective (unregularized Pi at the updated ratios),
  n_evaluations, status, tau, mean_abs_error, max_abs_error of the estimated ratio against
  the truth (mean of the 20-element halves);
- ``elements``: run x method x state x element: truth_ratio, updated_ratio (that state's
  own update), baseline_ratio (``soo`` methods), estimated_ratio, error, damage_index
  (1 - estimated ratio);
- ``pareto``: NSGA-II's final front: Pi_state1, Pi_state2, chosen;
- ``lcurve``: run x state x tau: residual_norm ||r|| = sqrt(Pi), solution_norm ||r - 1||,
  curvature, chosen.

Detections (threshold), comparisons and chosen tau per seed are analyses of these tables
(:mod:`framework.report.analyses.damage_summary`), so changing the threshold keeps every run.
"""

from __future__ import annotations

import logging
import time
from pathlib import Path
from typing import Literal

import numpy as np
from pydantic import Field, StrictInt, field_validator, model_validator

from framework.core.status import FAILURES, Status
from framework.study.kinds.base import ANALYSES, Kind, failure, task_key
from framework.study.schema import Strict, StudyHeader

log = logging.getLogger(__name__)

TABLES = ("runs", "states", "elements", "pareto", "lcurve")

PROCEDURES = ("single_objective", "nsga2", "tikhonov")
#: measured states, in the order of their noise streams
STATES = ("intact", "state1", "state2")
DAMAGED = ("state1", "state2")


# ---- schema ------------------------------------------------------------------------------
class PSOConfig(Strict):
    evaluations: StrictInt = Field(50_000, ge=20)
    swarm_size: StrictInt = Field(20, ge=2)


class NSGA2Config(Strict):
    pop_size: StrictInt = Field(500, ge=4)
    generations: StrictInt = Field(200, ge=1)


class LCurveConfig(Strict):
    tau_min: float = Field(1e-12, gt=0, strict=False)
    tau_max: float = Field(10.0, gt=0, strict=False)
    per_decade: StrictInt = Field(4, ge=1, le=50)

    @model_validator(mode="after")
    def _range(self):
        if not np.isfinite(self.tau_max) or self.tau_max <= self.tau_min:
            raise ValueError(f"tau_max must be finite and above tau_min, got {self.tau_min} .. {self.tau_max}")
        if self.taus().size < 5:
            raise ValueError("the tau grid needs at least 5 points (widen it or add points per decade)")
        return self

    def taus(self) -> np.ndarray:
        decades = np.log10(self.tau_max) - np.log10(self.tau_min)
        return np.logspace(np.log10(self.tau_min), np.log10(self.tau_max), int(round(decades * self.per_decade)) + 1)


class Config(StudyHeader):
    kind: Literal["damage"]
    procedures: list[Literal["single_objective", "nsga2", "tikhonov"]] = Field(
        default_factory=lambda: list(PROCEDURES))
    #: shape noise a in percent (SPEC 7: 3 %)
    noise_pct: float = Field(3.0, ge=0, le=50, strict=False)
    #: "truth": the 20-element truth (SPEC); "apriori": 10-element data (no discretization error)
    measured_mesh: Literal["truth", "apriori"] = "truth"
    n_modes: StrictInt = Field(5, ge=1, le=9)
    pso: PSOConfig = Field(default_factory=PSOConfig)
    nsga2: NSGA2Config = Field(default_factory=NSGA2Config)
    #: model evaluations of one sensitivity-method polish or L-curve step
    polish_evaluations: StrictInt = Field(3000, ge=10)
    lcurve: LCurveConfig = Field(default_factory=LCurveConfig)

    @field_validator("procedures")
    @classmethod
    def _procedures(cls, v):
        if not v or len(set(v)) != len(v):
            raise ValueError(f"give each procedure at most once and at least one, got {v}")
        return v



# ---- plan --------------------------------------------------------------------------------
def plan_runs(cfg: Config, sweep_values: dict) -> list[dict]:
    """One run per procedure and seed; a task holds only what its procedure uses."""
    data = cfg.model_dump(mode="json")
    common = {k: data[k] for k in ("noise_pct", "measured_mesh", "n_modes")}
    own = {"single_objective": ("pso", "polish_evaluations"), "nsga2": ("nsga2", "polish_evaluations"),
           "tikhonov": ("pso", "polish_evaluations", "lcurve")}
    parts = []
    for procedure in cfg.procedures:
        task = {**common, "procedure": procedure, **{k: data[k] for k in own[procedure]}}
        relevant = [k for k in sweep_values if k.split(".")[0] in (*common, *own[procedure])]
        columns = {"procedure": procedure, "noise_pct": float(cfg.noise_pct), "measured_mesh": cfg.measured_mesh}
        for i in range(cfg.runs):
            parts.append({"label": procedure, "seed": cfg.seed + i, "task": task, "columns": columns,
                          "relevant": relevant})
    return parts


def preflight(spec: dict, build_references: bool = True) -> None:
    """Build the model and one measurement of the run before any run starts."""
    measurements(spec["task"], spec["seed"])


def measurement_key(spec: dict) -> str:
    return task_key(spec, ("noise_pct", "measured_mesh", "n_modes"))


# ---- one run -----------------------------------------------------------------------------
def noise_seed(seed: int, state: str) -> int:
    """The seed of a state's noise draw: independent streams per state from the run's seed."""
    return int(np.random.SeedSequence([int(seed), STATES.index(state)]).generate_state(1)[0])


def measurements(task: dict, seed: int) -> dict:
    from framework.structures.beam import model as beam

    return {st: beam.measured(st, task["noise_pct"], noise_seed(seed, st), n_modes=task["n_modes"],
                              mesh=task["measured_mesh"]) for st in STATES}


def _budget(evaluations: int):
    """Only the evaluation count (and least squares' tolerances) end a run: Pi spans
    1e-9..1e-4 here, so the SPEC target (1e-6) and stall tolerance (1e-8) would stop a
    search far from the minimum (our assumption; the source states the 50 000 limit)."""
    from framework.optimizers import Budget

    return Budget(max_evaluations=evaluations, target_objective=None, stall_tolerance=0.0, stall_iterations=10**9)


def _sm(problem, x0: np.ndarray, evaluations: int):
    """The sensitivity method from x0: ``run_optimizer("sm", x0=...)`` (see damage.polish)."""
    from framework.damage import estimation as damage

    return damage.polish(problem, x0, evaluations)


class _Run:
    """The problems of one run and the rows it collects."""

    def __init__(self, spec: dict):
        from framework.structures.beam import model as beam
        from framework.updating.problem import UpdatingProblem

        self.spec, self.task, self.seed = spec, spec["task"], spec["seed"]
        self.model = beam.make_model(n_modes=max(7, self.task["n_modes"]))
        self.meas = measurements(self.task, self.seed)
        self.truth = {st: beam.equivalent_ratios(st) if st != "intact" else np.ones(10) for st in STATES}
        self._problem = UpdatingProblem
        self.tables: dict[str, list[dict]] = {t: [] for t in TABLES}
        self.n_evaluations = 0
        self.failed: list[str] = []

    def problem(self, state: str, tau: float = 0.0):
        from framework.updating.objectives import ObjectiveSpec

        return self._problem(self.model, self.meas[state], objective=ObjectiveSpec(regularization_tau=tau))

    def count(self, result) -> None:
        self.n_evaluations += int(result.n_evaluations)
        if result.status == Status.FAILED:
            self.failed.append(f"{result.algorithm}: {result.message}")

    def pi(self, state: str, ratios: np.ndarray) -> float:
        p = self.problem(state)
        return float(p.evaluate(p.parameters.to_normalized(ratios)[None, :]).objective[0])

    def record(self, method: str, state: str, ratios, n_evaluations: int, status: str, *, baseline=None,
               tau: float = np.nan) -> None:
        """Rows of one method's estimate of one state; ``baseline``: the intact update whose
        difference to ``ratios`` is the damage severity (source procedure)."""
        ratios = np.asarray(ratios, float)
        truth = self.truth[state]
        if not np.all(np.isfinite(ratios)):
            self.tables["states"].append({"method": method, "state": state, "objective": np.nan,
                                          "n_evaluations": int(n_evaluations), "status": Status.FAILED, "tau": tau,
                                          "mean_abs_error": np.nan, "max_abs_error": np.nan})
            return
        estimate = ratios if baseline is None else 1.0 - (np.asarray(baseline, float) - ratios)
        err = estimate - truth
        self.tables["states"].append({
            "method": method, "state": state, "objective": self.pi(state, ratios),
            "n_evaluations": int(n_evaluations), "status": status, "tau": tau,
            "mean_abs_error": float(np.abs(err).mean()), "max_abs_error": float(np.abs(err).max()),
        })
        for e in range(ratios.size):
            self.tables["elements"].append({
                "method": method, "state": state, "element": e + 1, "truth_ratio": float(truth[e]),
                "updated_ratio": float(ratios[e]),
                "baseline_ratio": float(baseline[e]) if baseline is not None else np.nan,
                "estimated_ratio": float(estimate[e]), "error": float(err[e]),
                "damage_index": float(1.0 - estimate[e]),
            })


def run(spec: dict) -> dict[str, list[dict]]:
    """One procedure on one measurement draw; a failed optimizer is a row, not an exception."""
    t0 = time.perf_counter()
    r = _Run(spec)
    procedure = spec["task"]["procedure"]
    {"single_objective": _single_objective, "nsga2": _nsga2, "tikhonov": _tikhonov}[procedure](r)
    r.tables["runs"].append({
        "objective": np.nan, "n_evaluations": r.n_evaluations, "wall_s": time.perf_counter() - t0,
        **(failure("; ".join(r.failed)) if r.failed else {"status": Status.OK, "error": ""}),
    })
    return r.tables


def _single_objective(r: _Run) -> None:
    from framework.optimizers import run_optimizer

    task = r.task
    pso, sm, pso_sm = {}, {}, {}
    for state in STATES:
        p = r.problem(state)
        res = run_optimizer("pso", p, r.seed, _budget(task["pso"]["evaluations"]),
                            swarm_size=task["pso"]["swarm_size"])
        r.count(res)
        pol = _sm(p, res.x_best if res.status != Status.FAILED else p.parameters.x_initial, task["polish_evaluations"])
        r.count(pol)
        direct = _sm(p, p.parameters.x_initial, task["polish_evaluations"])
        r.count(direct)
        pso[state] = (res.theta_best, res.n_evaluations, res.status)
        pso_sm[state] = (pol.theta_best, res.n_evaluations + pol.n_evaluations, res.status)
        sm[state] = (direct.theta_best, direct.n_evaluations, direct.status)
    for state in STATES:
        r.record("pso (ours)", state, *pso[state])
        r.record("pso+sm (ours)", state, *pso_sm[state])
        r.record("sm (ours)", state, *sm[state])
    for state in DAMAGED:
        for method, runs in (("soo", pso), ("soo+sm (ours)", pso_sm)):
            ratios, n_eval, status = runs[state]
            r.record(method, state, ratios, n_eval + runs["intact"][1], status, baseline=runs["intact"][0])


def _nsga2(r: _Run) -> None:
    from framework.damage import estimation as damage
    from framework.optimizers import run_optimizer

    task = r.task
    tp = damage.two_state(r.problem("state1"), r.problem("state2"))
    pop, gens = task["nsga2"]["pop_size"], task["nsga2"]["generations"]
    # a two-state point costs 2 model evaluations; only the generation count ends the run
    res = run_optimizer("nsga2", tp, r.seed, _budget(tp.evaluations_per_point * pop * gens), pop_size=pop,
                        n_generations=gens)
    r.count(res)
    if res.status == Status.FAILED:
        for state in DAMAGED:
            r.record("nsga2", state, np.full(10, np.nan), res.n_evaluations, Status.FAILED)
        return
    F, chosen = np.asarray(res.extra["pareto_F"]), int(res.extra["chosen_index"])
    for i, f in enumerate(F):
        r.tables["pareto"].append({"point": i, "Pi_state1": float(f[0]), "Pi_state2": float(f[1]),
                                   "chosen": i == chosen})
    for j, state in enumerate(DAMAGED):
        ratios = res.theta_best[10 * j: 10 * (j + 1)]
        r.record("nsga2", state, ratios, res.n_evaluations, res.status)
        p = r.problem(state)
        pol = _sm(p, p.parameters.to_normalized(ratios), task["polish_evaluations"])
        r.count(pol)
        r.record("nsga2+sm (ours)", state, pol.theta_best, res.n_evaluations + pol.n_evaluations, res.status)


def _tikhonov(r: _Run) -> None:
    from framework.damage import estimation as damage
    from framework.optimizers import run_optimizer

    task = r.task
    taus = LCurveConfig(**task["lcurve"]).taus()
    for state in DAMAGED:
        p0 = r.problem(state)
        start = _sm(p0, p0.parameters.x_initial, task["polish_evaluations"])
        r.count(start)
        x, n_eval, curve = start.x_best, start.n_evaluations, []
        for tau in taus:  # continuation along increasing tau
            step = _sm(r.problem(state, float(tau)), x, task["polish_evaluations"])
            r.count(step)
            n_eval += step.n_evaluations
            x = step.x_best
            ratios = p0.parameters.to_physical(x)
            residual = float(np.sqrt(p0.evaluate(x[None, :]).objective[0]))
            curve.append((float(tau), residual, float(np.linalg.norm(ratios - 1.0))))
        tau_arr, res_norm, sol_norm = (np.array(c) for c in zip(*curve))
        kappa = damage.lcurve_curvature(tau_arr, res_norm, sol_norm)
        corner = damage.lcurve_corner(tau_arr, res_norm, sol_norm)
        tau_star = float(tau_arr[corner])
        for i in range(len(curve)):
            r.tables["lcurve"].append({"state": state, "tau": tau_arr[i], "residual_norm": res_norm[i],
                                       "solution_norm": sol_norm[i], "curvature": kappa[i],
                                       "chosen": i == corner})
        pt = r.problem(state, tau_star)
        res = run_optimizer("pso", pt, r.seed, _budget(task["pso"]["evaluations"]),
                            swarm_size=task["pso"]["swarm_size"])
        r.count(res)
        r.record("pso_tikhonov", state, res.theta_best, n_eval + res.n_evaluations, res.status, tau=tau_star)
        start = res.x_best if res.status != Status.FAILED else pt.parameters.x_initial
        pol = _sm(pt, start, task["polish_evaluations"])
        r.count(pol)
        r.record("pso_tikhonov+sm (ours)", state, pol.theta_best, n_eval + res.n_evaluations + pol.n_evaluations,
                 res.status, tau=tau_star)


# ---- analyses and figures ----------------------------------------------------------------
DEFAULT_REPORT = {"damage_summary": {}}


def _report(report: dict) -> dict:
    return {**DEFAULT_REPORT, **(report or {})}


def analyses(tables: dict, report: dict) -> dict:
    """The comparison, damage-index and chosen-tau tables (``damage_summary``) and any
    other analysis named in ``report``."""
    from framework.report.analyses import run_analyses

    return run_analyses(tables, _report(report))


def figures(tables: dict, out_dir: Path, report: dict) -> list[Path]:
    from framework.report.analyses import analysis_figures

    return analysis_figures(tables, out_dir, _report(report))


# ---- mode shapes -------------------------------------------------------------------------
def shapes(cfg: Config, tables: dict, specs: list[dict]) -> list[tuple[str, object, dict[str, np.ndarray]]]:
    """Beam damage studies (kind ``damage``): per damaged state, the 10-element model against
    that state's measurement of the best estimate (lowest objective of the first planned
    variant, e.g. the SPEC's 3 % noise), at the intact ratios (``initial``) and at that
    method's own updated ratios (``updated``)."""
    import pandas as pd

    from framework.structures.beam import model as beam
    from framework.updating.problem import UpdatingProblem

    runs, states, elements = (tables.get(n) for n in ("runs", "states", "elements"))
    if runs is None or states is None or elements is None or states.empty or elements.empty:
        return []
    first_variant = specs[0]["variant"]
    by_key = {(s["label"], s["variant"], s["seed"]): s for s in specs}
    keyed = runs.set_index("run_id")
    out = []
    for state in DAMAGED:
        rows = states[(states["state"] == state) & ~states["status"].isin(FAILURES)
                      & np.isfinite(pd.to_numeric(states["objective"], errors="coerce"))]
        rows = rows[rows["run_id"].map(keyed["variant"]) == first_variant] if "variant" in keyed else rows
        if rows.empty:
            continue
        best = rows.sort_values(["objective", "run_id", "method"]).iloc[0]
        run = keyed.loc[best["run_id"]]
        spec = by_key.get((run["label"], run["variant"], int(run["seed"])))
        if spec is None:
            continue
        e = elements[(elements["run_id"] == best["run_id"]) & (elements["method"] == best["method"])
                     & (elements["state"] == state)].sort_values("element")
        task = spec["task"]
        model = beam.make_model(n_modes=max(7, int(task["n_modes"])))
        problem = UpdatingProblem(model, measurements(task, spec["seed"])[state])
        ratios = e["updated_ratio"].to_numpy(float)
        if ratios.size != len(problem.parameters):
            continue
        out.append((f"beam_{state}", problem, {"initial": np.ones(ratios.size), "updated": ratios}))
    return out


KIND = Kind(
    name="damage", config=Config, tables=TABLES, plan_runs=plan_runs, run=run, preflight=preflight,
    preflight_key=measurement_key, report=ANALYSES, analyses=analyses, figures=figures, shapes=shapes,
)
