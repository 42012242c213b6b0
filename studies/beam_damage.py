"""Damage estimation on the simulated beam (SPEC 7, issue 7): methods compared on noise seeds.

Run: ``nice -n 10 .venv/bin/python studies/beam_damage.py`` (full, ~20 min on one core) or
``--quick`` (smoke run). Writes under ``results/beam_damage/``: runs.csv, elements.csv,
summary.csv, pareto.csv, lcurve.csv, settings.json and figures (PNG).

Methods (per noise level and seed; the a-priori model is the 10-element numpy beam):

- ``sm``: sensitivity method (``run_optimizer("sm")``) from the initial model, per state;
- ``pso``: ``run_optimizer("pso")`` per state (swarm 20, factor 0.75); ``pso+sm``: PSO
  followed by a least-squares polish from its best point (hybrid);
- ``nsga2``: NSGA-II on both states at once (20 parameters, objectives [Pi_1, Pi_2]),
  the Pareto point nearest the ideal point; ``nsga2+sm``: that point polished per state;
- ``pso_tikhonov``: PSO (+ polish) on Pi + tau ||r - 1||^2 (r the I ratios, i.e. towards
  the initial model), tau at the corner of the L-curve. The L-curve is traced over a tau
  sweep by least-squares continuation from the unregularized ``pso+sm`` solution (cheap),
  the final regularized search at the chosen tau is a full PSO run plus polish.

Budgets are reduced from the source to fit 2 shared cores: PSO 10 000 evaluations per run
(source 50 000), NSGA-II population 500 for 40 generations (source 200; 5x fewer).
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from framework import damage
from framework.io import atomic_write_text, save_figure
from framework.models import beam
from framework.objectives import ObjectiveSpec
from framework.optimizers import Budget, run_optimizer
from framework.problem import UpdatingProblem

log = logging.getLogger("beam_damage")

STATES = ("state1", "state2")


@dataclass
class StudySettings:
    noise_pct: tuple[float, ...] = (0.0, 1.0, 3.0)
    seeds: int = 20
    seeds_noise_free: int = 5
    meshes_noise_free: tuple[str, ...] = ("truth", "apriori")
    pso_evaluations: int = 10_000
    pso_swarm: int = 20
    nsga2_pop: int = 500
    nsga2_generations: int = 40
    polish_evaluations: int = 3000
    taus: tuple[float, ...] = tuple(np.logspace(-9, -1, 17).tolist())
    threshold: float = damage.DETECTION_THRESHOLD
    out: str = "results/beam_damage"
    methods: tuple[str, ...] = ("sm", "pso", "pso+sm", "nsga2", "nsga2+sm", "pso_tikhonov")
    extra: dict = field(default_factory=dict)


def quick_settings(out: str) -> StudySettings:
    return StudySettings(
        noise_pct=(0.0, 3.0), seeds=1, seeds_noise_free=1, meshes_noise_free=("truth",),
        pso_evaluations=600, nsga2_pop=40, nsga2_generations=5, polish_evaluations=400,
        taus=tuple(np.logspace(-9, -1, 5).tolist()), out=out,
    )  # fmt: skip


def _pso_budget(s: StudySettings) -> Budget:
    # Pi spans 1e-9..1e-4 here: the SPEC target (1e-6) and stall tolerance (1e-8) would stop
    # PSO far from the minimum, so only the evaluation count ends a run
    return Budget(max_evaluations=s.pso_evaluations, target_objective=None, stall_tolerance=0.0,
                  stall_iterations=10**6)  # fmt: skip


def _element_rows(ratios, state, base: dict, threshold: float) -> list[dict]:
    truth = beam.equivalent_ratios(state)
    di = damage.damage_index(ratios)
    det = damage.detected(ratios, threshold)
    false = damage.false_detections(ratios, truth, threshold)
    return [
        {
            **base,
            "state": state,
            "element": e + 1,
            "truth": truth[e],
            "updated_ratio": float(ratios[e]),
            "error": float(ratios[e] - truth[e]),
            "abs_error": float(abs(ratios[e] - truth[e])),
            "damage_index": float(di[e]),
            "truly_damaged": bool(truth[e] < 1.0),
            "detected": "yes" if det[e] else "no",
            "false_detection": bool(false[e]),
        }  # fmt: skip
        for e in range(len(ratios))
    ]


def _run_row(base, state, method, problem0, ratios, n_eval, wall_s, status, threshold, **more) -> dict:
    """Run-level facts; objective = unregularized Pi of the state at the final ratios."""
    x = problem0.parameters.to_normalized(ratios)
    pi = float(problem0.evaluate(x[None, :]).objective[0])
    truth = beam.equivalent_ratios(state)
    err = np.abs(ratios - truth)
    return {
        **base, "state": state, "method": method, "objective": pi, "n_evaluations": int(n_eval),
        "wall_s": float(wall_s), "status": status, "mean_abs_error": float(err.mean()),
        "max_abs_error": float(err.max()),
        "n_false_detections": int(damage.false_detections(ratios, truth, threshold).sum()),
        "n_missed": int(np.sum((truth < 1.0) & ~damage.detected(ratios, threshold))), **more,
    }  # fmt: skip


def run_case(noise_pct: float, seed: int, mesh: str, s: StudySettings):
    """All methods on one measurement draw; returns (runs, elements, pareto, lcurve) row lists."""
    model = beam.make_model()
    base = {"study": "beam_damage", "noise_pct": noise_pct, "seed": seed, "mesh": mesh}
    runs, elements, pareto, lcurve = [], [], [], []
    meas = {st: beam.measured(st, noise_pct, seed, mesh=mesh) for st in STATES}

    def new_problem(state: str, tau: float = 0.0) -> UpdatingProblem:
        return UpdatingProblem(model, meas[state], objective=ObjectiveSpec(regularization_tau=tau))

    def ratios_of(problem, x):
        return problem.parameters.to_physical(x)

    pso_budget = _pso_budget(s)

    def record(state, method, ratios, n_eval, wall_s, status, **more):
        runs.append(_run_row({**base, "method": method}, state, method, new_problem(state), ratios, n_eval,
                             wall_s, status, s.threshold, **more))  # fmt: skip
        elements.extend(_element_rows(ratios, state, {**base, "method": method}, s.threshold))

    for state in STATES:
        if "sm" in s.methods:
            p = new_problem(state)
            # only the evaluation count and least squares' tolerances end SM here (Pi spans
            # 1e-9..1e-4, below the SPEC stall tolerance and target)
            sm_budget = Budget(max_evaluations=s.polish_evaluations, target_objective=None, stall_tolerance=0.0)
            r = run_optimizer("sm", p, seed, sm_budget, diff_step=1e-6)
            record(state, "sm", r.theta_best, r.n_evaluations, r.wall_s, r.status)
        p = new_problem(state)
        r = run_optimizer("pso", p, seed, pso_budget, swarm_size=s.pso_swarm)
        record(state, "pso", r.theta_best, r.n_evaluations, r.wall_s, r.status)
        polished = damage.polish(p, r.x_best, s.polish_evaluations)
        x_pso_sm = polished.x_best
        record(state, "pso+sm", ratios_of(p, x_pso_sm), r.n_evaluations + polished.n_evaluations,
               r.wall_s + polished.wall_s, r.status)  # fmt: skip
        if "pso_tikhonov" in s.methods:
            t0 = time.perf_counter()
            n_eval, curve = 0, []
            x_prev = x_pso_sm
            for tau in s.taus:  # continuation along increasing tau
                pt = new_problem(state, tau)
                step = damage.polish(pt, x_prev, s.polish_evaluations)
                x_prev = step.x_best
                n_eval += step.n_evaluations
                ratios = ratios_of(pt, x_prev)
                fit = float(new_problem(state).evaluate(x_prev[None, :]).objective[0])
                curve.append((tau, np.sqrt(fit), float(np.linalg.norm(ratios - 1.0))))
            corner = damage.lcurve_corner([c[1] for c in curve], [c[2] for c in curve])
            tau_star = curve[corner][0]
            for i, (tau, fit, norm) in enumerate(curve):
                lcurve.append({**base, "state": state, "tau": tau, "fit_norm": fit, "solution_norm": norm,
                               "chosen": i == corner})  # fmt: skip
            pt = new_problem(state, tau_star)
            rt = run_optimizer("pso", pt, seed, pso_budget, swarm_size=s.pso_swarm)
            final = damage.polish(pt, rt.x_best, s.polish_evaluations)
            record(state, "pso_tikhonov", ratios_of(pt, final.x_best), n_eval + rt.n_evaluations + final.n_evaluations,
                   time.perf_counter() - t0, rt.status, tau=tau_star)  # fmt: skip

    if "nsga2" in s.methods:
        tp = damage.two_state(new_problem("state1"), new_problem("state2"))
        # a two-state point costs 2 model evaluations; only the generation count ends the run
        nsga2_budget = Budget(max_evaluations=2 * s.nsga2_pop * s.nsga2_generations, target_objective=None,
                              stall_tolerance=0.0)  # fmt: skip
        r = run_optimizer("nsga2", tp, seed, nsga2_budget, pop_size=s.nsga2_pop, n_generations=s.nsga2_generations)
        F, chosen = r.extra["pareto_F"], r.extra["chosen_index"]
        for i, f in enumerate(F):
            pareto.append({**base, "point": i, "Pi_state1": f[0], "Pi_state2": f[1], "chosen": i == chosen})
        for j, state in enumerate(STATES):
            ratios = r.theta_best[10 * j : 10 * (j + 1)]
            record(state, "nsga2", ratios, r.n_evaluations, r.wall_s, r.status, pareto_size=len(F))
            p = new_problem(state)
            polished = damage.polish(p, p.parameters.to_normalized(ratios), s.polish_evaluations)
            record(state, "nsga2+sm", ratios_of(p, polished.x_best), r.n_evaluations + polished.n_evaluations,
                   r.wall_s + polished.wall_s, r.status)  # fmt: skip
    return runs, elements, pareto, lcurve


def summarize(runs: pd.DataFrame) -> pd.DataFrame:
    """Per noise level, mesh, method and state: element errors and detections over seeds."""
    g = runs.groupby(["noise_pct", "mesh", "method", "state"], sort=True)
    return g.agg(
        n_seeds=("seed", "nunique"),
        mean_abs_error=("mean_abs_error", "mean"),
        max_abs_error=("max_abs_error", "max"),
        median_max_abs_error=("max_abs_error", "median"),
        false_detections=("n_false_detections", "sum"),
        false_detections_per_run=("n_false_detections", "mean"),
        missed=("n_missed", "sum"),
        mean_objective=("objective", "mean"),
        mean_evaluations=("n_evaluations", "mean"),
        mean_wall_s=("wall_s", "mean"),
    ).reset_index()


def comparison_table(runs: pd.DataFrame, noise_pct: float, mesh: str = "truth") -> pd.DataFrame:
    """One row per method, both states side by side, on the same seeds (SPEC 7 comparison)."""
    d = runs[(runs.noise_pct == noise_pct) & (runs.mesh == mesh) & runs.method.notna()]
    g = d.groupby(["method", "state"]).agg(
        seeds=("seed", "nunique"),
        mean_error=("mean_abs_error", "mean"),
        max_error=("max_abs_error", "max"),
        false_detections=("n_false_detections", "sum"),
        missed=("n_missed", "sum"),
        evaluations=("n_evaluations", "mean"),
    )
    wide = g.unstack("state")
    wide.columns = [f"{state}_{name}" for name, state in wide.columns]
    return wide.reset_index()


def write_tables(out: Path, tables: dict[str, list[dict]]) -> dict[str, pd.DataFrame]:
    frames = {name: pd.DataFrame(rows) for name, rows in tables.items()}
    for name, df in frames.items():
        atomic_write_text(out / f"{name}.csv", df.to_csv(index=False))
    if len(frames["runs"]):
        summary = summarize(frames["runs"])
        atomic_write_text(out / "summary.csv", summary.to_csv(index=False, float_format="%.5g"))
        frames["summary"] = summary
        for noise in sorted(set(frames["runs"].noise_pct)):
            table = comparison_table(frames["runs"], noise)
            if len(table):
                text = table.to_csv(index=False, float_format="%.4g")
                atomic_write_text(out / f"comparison_noise{noise:g}.csv", text)
    return frames


def make_figures(out: Path, noise_pct: float = 3.0) -> list[Path]:
    """Figures drawn from the tables only."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import seaborn as sns

    elements = pd.read_csv(out / "elements.csv")
    paths = []
    sel = elements[(elements.noise_pct == noise_pct) & (elements.mesh == "truth")]
    if sel.empty:
        return paths
    for quantity, fname, ylabel in (
        ("updated_ratio", "element_ratios", "updated I ratio (1 sd over seeds)"),
        ("damage_index", "damage_index", "damage index 1 - r (95% CI of the mean over seeds)"),
    ):
        fig, axes = plt.subplots(2, 1, figsize=(12, 8), sharex=True)
        for ax, state in zip(axes, STATES):
            d = sel[sel.state == state]
            if quantity == "updated_ratio":
                sns.pointplot(d, x="element", y=quantity, hue="method", errorbar="sd", dodge=0.6,
                              linestyle="none", markersize=4, err_kws={"linewidth": 1}, ax=ax)  # fmt: skip
            else:
                sns.barplot(d, x="element", y=quantity, hue="method", errorbar=("ci", 95), ax=ax)
            truth = beam.equivalent_ratios(state)
            ref = truth if quantity == "updated_ratio" else 1.0 - truth
            ax.scatter(np.arange(10), ref, marker="_", s=600, color="k", zorder=5, label="truth")
            if quantity == "damage_index":
                ax.axhline(damage.DETECTION_THRESHOLD, ls="--", color="grey", lw=1, label="threshold")
            ax.set_title(f"{state}, {noise_pct:g} % shape noise (mean, error bar = {ylabel.split('(')[-1]}")
            ax.set_ylabel(ylabel.split(" (")[0])
            ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
        fig.tight_layout()
        path = out / f"{fname}_noise{noise_pct:g}.png"
        save_figure(fig, path, dpi=120, tight=False)
        paths.append(path)
    pareto = pd.read_csv(out / "pareto.csv")
    pareto = pareto[(pareto.noise_pct == noise_pct) & (pareto.mesh == "truth")]
    if len(pareto):
        seed = int(pareto.seed.min())
        d = pareto[pareto.seed == seed]
        fig, ax = plt.subplots(figsize=(5, 4))
        ax.scatter(d.Pi_state1, d.Pi_state2, s=12, label="final Pareto front")
        c = d[d.chosen]
        ax.scatter(c.Pi_state1, c.Pi_state2, s=60, color="r", marker="*", label="nearest ideal point")
        ax.set_xscale("log"), ax.set_yscale("log")
        ax.set_xlabel("Pi state 1"), ax.set_ylabel("Pi state 2")
        ax.set_title(f"NSGA-II, seed {seed}, {noise_pct:g} % noise")
        ax.legend()
        fig.tight_layout()
        path = out / f"pareto_noise{noise_pct:g}.png"
        save_figure(fig, path, dpi=120, tight=False)
        paths.append(path)
    lc = pd.read_csv(out / "lcurve.csv")
    lc = lc[(lc.noise_pct == noise_pct) & (lc.mesh == "truth")]
    if len(lc):
        seed = int(lc.seed.min())
        fig, axes = plt.subplots(1, 2, figsize=(10, 4))
        for ax, state in zip(axes, STATES):
            d = lc[(lc.seed == seed) & (lc.state == state)]
            ax.loglog(d.fit_norm, d.solution_norm, "o-", ms=4)
            for _, row in d.iterrows():
                ax.annotate(f"{row.tau:.0e}", (row.fit_norm, row.solution_norm), fontsize=6)
            c = d[d.chosen]
            ax.loglog(c.fit_norm, c.solution_norm, "r*", ms=14, label=f"corner tau={c.tau.iloc[0]:.1e}")
            ax.set_xlabel("sqrt(Pi) (fit)"), ax.set_ylabel("||r - 1|| (solution norm)")
            ax.set_title(f"L-curve {state}, seed {seed}, {noise_pct:g} % noise")
            ax.legend()
        fig.tight_layout()
        path = out / f"lcurve_noise{noise_pct:g}.png"
        save_figure(fig, path, dpi=120, tight=False)
        paths.append(path)
    return paths


def run_study(s: StudySettings) -> dict[str, pd.DataFrame]:
    out = Path(s.out)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out / "settings.json", json.dumps(asdict(s), indent=2))
    tables: dict[str, list[dict]] = {"runs": [], "elements": [], "pareto": [], "lcurve": []}
    cases = []
    for noise in s.noise_pct:
        meshes = s.meshes_noise_free if noise == 0 else ("truth",)
        n_seeds = s.seeds_noise_free if noise == 0 else s.seeds
        cases += [(noise, seed, mesh) for mesh in meshes for seed in range(n_seeds)]
    frames: dict[str, pd.DataFrame] = {}
    for i, (noise, seed, mesh) in enumerate(cases):
        t0 = time.perf_counter()
        try:
            parts = run_case(noise, seed, mesh, s)
        except Exception as exc:  # a failed case is recorded, the sweep goes on
            log.exception("case noise=%s seed=%s mesh=%s failed", noise, seed, mesh)
            tables["runs"].append({"study": "beam_damage", "noise_pct": noise, "seed": seed, "mesh": mesh,
                                   "status": "error", "error": repr(exc)})  # fmt: skip
            continue
        for name, rows in zip(tables, parts):
            tables[name].extend(rows)
        frames = write_tables(out, tables)
        log.info("case %d/%d noise=%g seed=%d mesh=%s done in %.1f s", i + 1, len(cases), noise, seed, mesh,
                 time.perf_counter() - t0)  # fmt: skip
    for noise in s.noise_pct:
        if noise > 0:
            make_figures(out, noise)
    return frames


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="smoke run: 1 seed, tiny budgets")
    ap.add_argument("--seeds", type=int, default=None)
    ap.add_argument("--out", default=None)
    ap.add_argument("--tables-only", action="store_true", help="rebuild summary, comparison and figures from CSVs")
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(message)s")
    s = quick_settings(args.out or "results/beam_damage/quick") if args.quick else StudySettings()
    if args.out:
        s.out = args.out
    if args.seeds is not None:
        s.seeds = args.seeds
    if args.tables_only:
        out = Path(s.out)
        names = ("runs", "elements", "pareto", "lcurve")
        frames = write_tables(out, {n: pd.read_csv(out / f"{n}.csv").to_dict("records") for n in names})
        for noise in sorted(set(frames["runs"].noise_pct)):
            if noise > 0:
                make_figures(out, noise)
    else:
        frames = run_study(s)
    if "summary" in frames:
        print(frames["summary"].to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
