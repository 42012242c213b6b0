"""Study of issue 6: the detailed lab-frame model - sensitivity, updating, validation.

Reads ``studies/lab_frame_detailed.yaml`` (the framework's study-config schema) and writes,
under ``results/lab_frame_detailed/``, tidy tables

    runs.csv         one row per run (structure, algorithm, seed, objective, evaluations, ...)
    parameters.csv   one row per run and parameter (value, ratio to initial, normalized)
    modes.csv        one row per run, case (base + the two added-mass cases) and mode
    history.csv      one row per run and evaluation (best objective so far)
    sensitivity.csv  one row per parameter and mode (relative frequency and MAC sensitivity)
    comparison.csv   validation of the best detailed and best 3-DOF run, side by side

and figures (sensitivity bars, convergence, parameter spread, validation errors), plus a
short README.md with the key numbers. Figures are drawn from the tables only.

Usage: ``.venv/bin/python studies/lab_frame_detailed.py [config.yaml] [--runs N]``.
Written as a script because the framework's study runner did not exist yet; the config
can be run by ``gomu run`` once it does (the ``options`` block is this script's extra).
"""

from __future__ import annotations

import argparse
import logging
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd

from framework.io import atomic_write_text, save_figure
from framework.models.registry import builtin_measured, make_structure
from framework.objectives import ObjectiveSpec
from framework.optimizers import Budget, run_optimizer
from framework.problem import UpdatingProblem
from framework.study.config import StudyConfig, load

log = logging.getLogger("studies.lab_frame_detailed")
ROOT = Path(__file__).resolve().parents[1]
DEFAULT_CONFIG = ROOT / "studies" / "lab_frame_detailed.yaml"


# ------------------------------------------------------------------------ problem set-up
def objective_spec(cfg: StudyConfig) -> ObjectiveSpec:
    o = cfg.objective
    return ObjectiveSpec(
        alpha=o.alpha,
        beta=o.beta,
        use_shapes=o.use_shapes,
        pairing=o.pairing,
        mac_threshold=o.mac_threshold,
        frequency_window=o.frequency_window,
        unmatched_penalty=o.unmatched_penalty,
        failure_penalty=o.failure_penalty,
    )


def make_problem(cfg, structure, options, names, bounds, case="base", measured_case=None):
    """UpdatingProblem for ``structure`` with ``options``; names None = all parameters."""
    model = make_structure(structure, **options)
    params = model.parameters
    if bounds:
        params = params.with_bounds({k: tuple(v) for k, v in bounds.items()})
    if names:
        params = params.subset(names)
    measured = builtin_measured(cfg.measured.builtin, measured_case or case)
    return UpdatingProblem(model, measured, parameters=params, objective=objective_spec(cfg), name=structure)


def cases(cfg: StudyConfig) -> list[tuple[str, dict, str]]:
    """(case name, structure options, measured case) for the base and validation cases."""
    out = [("base", dict(cfg.structure.options), cfg.measured.case)]
    for v in cfg.validation:
        out.append((v.case, {**cfg.structure.options, **v.structure_options}, v.measured.case))
    return out


# ------------------------------------------------------------------------ sensitivity
def sensitivity_table(
    cfg: StudyConfig,
    names: list[str] | None,
    rel_step: float,
    at: dict[str, float] | None = None,
    point: str = "initial",
) -> pd.DataFrame:
    """Relative sensitivities by forward differences at the initial model (or at ``at``):

    S_f = (f_i(theta_j (1 + h)) - f_i) / (f_i h),  S_MAC = (MAC_i(theta_j (1 + h)) - MAC_i) / h
    for the analytical modes paired with measured modes 1..3 (h = rel_step), computed by
    :func:`framework.sensitivity.sensitivity_matrix` with the bounds widened to
    [0.01, 2] x initial so that the step is never clipped at a bound.
    """
    from framework.sensitivity import sensitivity_matrix

    model = make_structure(cfg.structure.name, **cfg.structure.options)
    params = model.parameters.subset(names) if names else model.parameters
    measured = builtin_measured(cfg.measured.builtin, cfg.measured.case)
    problem = UpdatingProblem(model, measured, parameters=params, objective=objective_spec(cfg))
    theta0 = problem.parameters.initial.copy()
    for name, value in (at or {}).items():
        theta0[problem.parameters.names.index(name)] = value
    res = sensitivity_matrix(problem, theta0=theta0, rel_step=rel_step, widen=(0.01, 2.0))
    rows = []
    for j, name in enumerate(res.parameters):
        for i, label in enumerate(res.modes):
            rows.append(
                {
                    "point": point,
                    "parameter": name,
                    "value": theta0[j],
                    "mode": i + 1,
                    "label": label,
                    "f_model_hz": res.f_model_hz[i],
                    "rel_sensitivity_frequency": res.frequency[i, j],
                    "rel_sensitivity_mac": res.mac[i, j],
                    "rel_step": rel_step,
                }
            )
    return pd.DataFrame(rows)


def inset_scan(cfg: StudyConfig, insets_m: list[float]) -> pd.DataFrame:
    """How the open geometric choice ``column_inset_m`` changes the initial model and the
    result of updating (k_r2, k_r3 with the sensitivity method from the initial values)."""
    rows = []
    for inset in insets_m:
        options = {**cfg.structure.options, "column_inset_m": float(inset)}
        problem = make_problem(cfg, cfg.structure.name, options, cfg.parameters.names, cfg.parameters.bounds)
        f0 = problem.correlation_at(problem.parameters.initial).f_model_hz
        res = run_optimizer("sm", problem, seed=0, budget=Budget(max_evaluations=500))
        corr = problem.correlation_at(res.theta_best)
        row = {"column_inset_m": inset, "objective": res.objective}
        row |= {f"f{i + 1}_initial_hz": f for i, f in enumerate(f0)}
        row |= dict(zip(problem.parameters.names, res.theta_best))
        row |= {f"f{i + 1}_updated_hz": f for i, f in enumerate(corr.f_model_hz)}
        row |= {f"error{i + 1}_updated_pct": 100 * e for i, e in enumerate(corr.frequency_error)}
        rows.append(row)
    return pd.DataFrame(rows)


# ------------------------------------------------------------------------ updating
def run_updating(cfg: StudyConfig, structure: str, options: dict, names, bounds, n_runs: int) -> dict:
    """All algorithm runs on one structure; returns the tidy tables as DataFrames."""
    run_rows, par_rows, mode_rows, hist_rows = [], [], [], []
    problem = make_problem(cfg, structure, options, names, bounds)
    validation = {
        case: make_problem(cfg, structure, opts, names, bounds, measured_case=mcase) for case, opts, mcase in cases(cfg)
    }

    def add_modes(run_id, algorithm, seed, theta):
        for case, prob in validation.items():
            table = prob.mode_table(theta)
            for row in table.to_dict("records"):
                mode_rows.append(
                    {
                        "run_id": run_id,
                        "structure": structure,
                        "algorithm": algorithm,
                        "seed": seed,
                        "case": case,
                    }
                    | row
                )

    def add_parameters(run_id, algorithm, seed, theta):
        p = problem.parameters
        for k, name in enumerate(p.names):
            par_rows.append(
                {
                    "run_id": run_id,
                    "structure": structure,
                    "algorithm": algorithm,
                    "seed": seed,
                    "parameter": name,
                    "unit": p[k].unit,
                    "value": theta[k],
                    "initial": p.initial[k],
                    "ratio": theta[k] / p.initial[k] if p.initial[k] != 0 else np.nan,
                    "normalized": p.to_normalized(theta)[k],
                    "lower": p.lower[k],
                    "upper": p.upper[k],
                }
            )

    theta0 = problem.parameters.initial
    pi0 = problem.objective1(problem.x_initial)
    run_id = f"{structure}:initial"
    run_rows.append(
        {
            "run_id": run_id,
            "structure": structure,
            "algorithm": "initial",
            "seed": -1,
            "objective": pi0,
            "n_evaluations": 1,
            "n_iterations": 0,
            "wall_s": 0.0,
            "status": "initial",
            "message": "",
            "n_failed": 0,
        }
    )
    add_parameters(run_id, "initial", -1, theta0)
    add_modes(run_id, "initial", -1, theta0)

    for key, alg in cfg.algorithms.items():
        budget = Budget(**(cfg.budget.model_dump() | alg.budget))
        runs = alg.runs or n_runs
        for r in range(runs):
            seed = cfg.seed + r
            t0 = time.perf_counter()
            try:
                res = run_optimizer(alg.algorithm, problem, seed=seed, budget=budget, **alg.settings)
            except Exception as exc:  # a failed run is recorded, the study goes on
                log.exception("run %s seed %d failed", key, seed)
                run_rows.append(
                    {
                        "run_id": f"{structure}:{key}:{seed}",
                        "structure": structure,
                        "algorithm": key,
                        "seed": seed,
                        "objective": np.nan,
                        "n_evaluations": 0,
                        "n_iterations": 0,
                        "wall_s": time.perf_counter() - t0,
                        "status": "error",
                        "message": repr(exc),
                        "n_failed": 0,
                    }
                )
                continue
            run_id = f"{structure}:{key}:{seed}"
            log.info(
                "%s %s seed %d: Pi = %.4g after %d evaluations (%s)",
                structure,
                key,
                seed,
                res.objective,
                res.n_evaluations,
                res.status,
            )
            run_rows.append(
                {
                    "run_id": run_id,
                    "structure": structure,
                    "algorithm": key,
                    "seed": seed,
                    "objective": res.objective,
                    "n_evaluations": res.n_evaluations,
                    "n_iterations": res.n_iterations,
                    "wall_s": res.wall_s,
                    "status": res.status,
                    "message": res.message,
                    "n_failed": res.n_failed,
                }
            )
            add_parameters(run_id, key, seed, res.theta_best)
            add_modes(run_id, key, seed, res.theta_best)
            for e, best in enumerate(np.asarray(res.history, float), start=1):
                hist_rows.append(
                    {
                        "run_id": run_id,
                        "structure": structure,
                        "algorithm": key,
                        "seed": seed,
                        "evaluation": e,
                        "best_objective": best,
                    }
                )
    return {
        "runs": pd.DataFrame(run_rows),
        "parameters": pd.DataFrame(par_rows),
        "modes": pd.DataFrame(mode_rows),
        "history": pd.DataFrame(hist_rows),
    }


def best_runs(runs: pd.DataFrame) -> pd.DataFrame:
    """The best run of each structure and algorithm (lowest objective)."""
    ok = runs.dropna(subset=["objective"])
    return ok.loc[ok.groupby(["structure", "algorithm"])["objective"].idxmin()]


def comparison_table(runs: pd.DataFrame, modes: pd.DataFrame) -> pd.DataFrame:
    """Validation of each structure's best run (all algorithms) and its initial model."""
    best = best_runs(runs)
    keep = best.loc[best.groupby("structure")["objective"].idxmin(), "run_id"].tolist()
    keep += runs.loc[runs["algorithm"] == "initial", "run_id"].tolist()
    cols = [
        "structure",
        "algorithm",
        "seed",
        "case",
        "mode",
        "label",
        "f_measured_hz",
        "f_model_hz",
        "error_pct",
        "mac",
        "matched",
    ]
    return modes[modes["run_id"].isin(keep)][cols].sort_values(["structure", "algorithm", "case", "mode"])


# ------------------------------------------------------------------------ figures
def _save(fig, path: Path) -> None:
    save_figure(fig, path, dpi=130)


def figures(out: Path, tables: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import seaborn as sns

    sens = tables["sensitivity"]
    points = list(dict.fromkeys(sens["point"]))
    fig, axes = plt.subplots(len(points), 2, figsize=(11, 3.6 * len(points)), squeeze=False)
    for row, point in zip(axes, points):
        sub = sens[sens["point"] == point]
        sns.barplot(sub, x="parameter", y="rel_sensitivity_frequency", hue="label", ax=row[0])
        row[0].set_ylabel("(df/f) / (dk/k)")
        row[0].set_title(f"frequency sensitivity ({point} model)")
        sns.barplot(sub, x="parameter", y="rel_sensitivity_mac", hue="label", ax=row[1])
        row[1].set_ylabel("dMAC / (dk/k)")
        row[1].set_title(f"MAC sensitivity ({point} model)")
    fig.tight_layout()
    _save(fig, out / "sensitivity.png")

    hist = tables["history"]
    fig, ax = plt.subplots(figsize=(6.5, 4))
    for (structure, alg), grp in hist.groupby(["structure", "algorithm"]):
        for i, (_, run) in enumerate(grp.groupby("run_id")):
            ax.plot(
                run["evaluation"],
                run["best_objective"],
                lw=1,
                color="C0" if structure.endswith("detailed") else "C1",
                ls="-" if alg == "pso" else "--",
                label=f"{structure} {alg}" if i == 0 else None,
            )
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("model evaluations")
    ax.set_ylabel("best objective Pi")
    ax.legend(fontsize=8)
    _save(fig, out / "convergence.png")

    pars = tables["parameters"]
    pars = pars[pars["algorithm"] != "initial"]
    fig, ax = plt.subplots(figsize=(7, 3.5))
    sns.stripplot(pars, x="parameter", y="ratio", hue="algorithm", dodge=True, ax=ax)
    ax.set_ylabel("updated / initial")
    ax.set_title("updated parameters over runs")
    _save(fig, out / "parameters.png")

    comp = tables["comparison"].copy()
    comp["model"] = comp["structure"] + " " + comp["algorithm"]
    g = sns.catplot(comp, x="label", y="error_pct", hue="model", col="case", kind="bar", height=3.2, aspect=1.1)
    for ax in g.axes.flat:
        ax.axhline(0, color="k", lw=0.6)
    g.set_axis_labels("", "frequency error (%)")
    _save(g.figure, out / "validation.png")
    plt.close(g.figure)


# ------------------------------------------------------------------------ report
def _markdown(df: pd.DataFrame, floatfmt: str = "{:.4g}") -> str:
    cols = list(df.columns)
    lines = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    for row in df.itertuples(index=False):
        cells = [floatfmt.format(v) if isinstance(v, float) else str(v) for v in row]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def summary(tables: dict, cfg: StudyConfig, elapsed_s: float) -> str:
    runs = tables["runs"]
    agg = (
        runs[runs["algorithm"] != "initial"]
        .groupby(["structure", "algorithm"])
        .agg(
            runs=("seed", "size"),
            best=("objective", "min"),
            mean=("objective", "mean"),
            worst=("objective", "max"),
            mean_evaluations=("n_evaluations", "mean"),
            mean_wall_s=("wall_s", "mean"),
        )
        .reset_index()
    )
    pars = tables["parameters"]
    spread = (
        pars[pars["algorithm"] != "initial"]
        .groupby(["structure", "algorithm", "parameter"])["value"]
        .agg(["mean", "std", "min", "max"])
        .reset_index()
    )
    sens = tables["sensitivity"].pivot(
        index=["point", "parameter"], columns="label", values="rel_sensitivity_frequency"
    )
    comp = tables["comparison"].drop(columns=["matched"])
    sections = [
        f"# {cfg.study}\n\n{cfg.description.strip()}\n\nGenerated by `studies/lab_frame_detailed.py` "
        f"in {elapsed_s:.0f} s. Tables: runs.csv, parameters.csv, modes.csv, history.csv, "
        "sensitivity.csv, comparison.csv, inset_scan.csv; figures: sensitivity.png, convergence.png, "
        "parameters.png, validation.png.",
        "## Key results\n\n" + key_results(tables, cfg),
        "## Relative frequency sensitivities, (df/f)/(dk/k), initial and updated model\n\n"
        + _markdown(sens.reset_index()),
        "## Runs\n\n" + _markdown(agg),
        "## Updated parameters over runs\n\n" + _markdown(spread),
        "## Validation: best run of each model and the initial models\n\n" + _markdown(comp),
    ]
    if "inset_scan" in tables:
        sections.append(
            "## Open geometric choice: distance of the column axes from the slab edges\n\n"
            "Each row re-runs SM (k_r2, k_r3 from their initial values) with another `column_inset_m`.\n\n"
            + _markdown(tables["inset_scan"])
        )
    return "\n\n".join(sections) + "\n"


#: Initial frequencies of the source's detailed model (SPEC 5), for comparison only.
SOURCE_INITIAL_HZ = (3.58, 7.97, 10.29)


def key_results(tables: dict, cfg: StudyConfig) -> str:
    """A few sentences with the headline numbers, computed from the tables."""
    comp = tables["comparison"]
    det = comp[comp["structure"] == cfg.structure.name]
    init = det[(det["algorithm"] == "initial") & (det["case"] == "base")]["f_model_hz"].to_numpy()
    upd = det[det["algorithm"] != "initial"]
    pars = tables["parameters"]
    best_id = best_runs(tables["runs"]).query("structure == @cfg.structure.name").sort_values("objective")
    best_id = best_id["run_id"].iloc[0]
    bp = pars[pars["run_id"] == best_id]
    lines = [
        "- Initial detailed model: "
        + ", ".join(f"{f:.2f}" for f in init)
        + " Hz (source's detailed model: "
        + ", ".join(f"{f:.2f}" for f in SOURCE_INITIAL_HZ)
        + " Hz; measured 3.58, 5.01, 7.28 Hz).",
        f"- Best updated point ({best_id}): "
        + ", ".join(f"{r.parameter} = {r.value:.1f} {r.unit} ({r.ratio:.3f} x initial)" for r in bp.itertuples()),
    ]
    for structure, grp in comp[comp["algorithm"] != "initial"].groupby("structure"):
        for case, sub in grp.groupby("case"):
            lines.append(
                f"- {structure}, {case}: max |frequency error| {sub['error_pct'].abs().max():.2f} %, "
                f"min MAC {sub['mac'].min():.3f}"
            )
    spread = tables["runs"].query("structure == @cfg.structure.name and algorithm != 'initial'")
    lines.append(
        f"- {cfg.structure.name}: objective over all runs {spread['objective'].min():.4g} to "
        f"{spread['objective'].max():.4g} ({len(spread)} runs)."
    )
    del upd
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("config", nargs="?", default=str(DEFAULT_CONFIG))
    ap.add_argument("--runs", type=int, default=None, help="override the number of runs per algorithm")
    ap.add_argument("--output", default=None, help="override the output directory")
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(message)s")
    cfg = load(args.config)
    out = Path(args.output) if args.output else cfg.output_dir(ROOT)
    out.mkdir(parents=True, exist_ok=True)
    n_runs = args.runs or cfg.runs
    t0 = time.perf_counter()

    sens_opts = cfg.options.get("sensitivity", {})
    sens_names, rel_step = sens_opts.get("parameters"), sens_opts.get("rel_step", 1e-3)
    tables = {"sensitivity": sensitivity_table(cfg, sens_names, rel_step)}
    parts = [
        run_updating(
            cfg,
            cfg.structure.name,
            cfg.structure.options,
            cfg.parameters.names,
            cfg.parameters.bounds,
            n_runs,
        )
    ]
    ref = cfg.options.get("compare_3dof")
    if ref:
        parts.append(run_updating(cfg, ref["structure"], {}, ref.get("parameters"), ref.get("bounds") or {}, n_runs))
    for name in ("runs", "parameters", "modes", "history"):
        df = pd.concat([p[name] for p in parts], ignore_index=True)
        df.insert(0, "study", cfg.study)
        tables[name] = df
    tables["comparison"] = comparison_table(tables["runs"], tables["modes"])
    # sensitivities again at the best updated point of the detailed model
    best = best_runs(tables["runs"])
    best = best[best["structure"] == cfg.structure.name].sort_values("objective").iloc[0]
    pars = tables["parameters"]
    updated = pars[pars["run_id"] == best["run_id"]].set_index("parameter")["value"].to_dict()
    tables["sensitivity"] = pd.concat(
        [tables["sensitivity"], sensitivity_table(cfg, sens_names, rel_step, at=updated, point="updated")],
        ignore_index=True,
    )
    if cfg.options.get("inset_scan"):
        tables["inset_scan"] = inset_scan(cfg, cfg.options["inset_scan"])
    for name, df in tables.items():
        atomic_write_text(out / f"{name}.csv", df.to_csv(index=False))
    figures(out, tables)
    atomic_write_text(out / "README.md", summary(tables, cfg, time.perf_counter() - t0))
    atomic_write_text(out / "config.yaml", Path(args.config).read_text())
    log.info("wrote %s in %.1f s", out, time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    sys.exit(main())
