"""Rows of the reproduction report for the beam damage study (SPEC 7), from committed tables.

``rows(results_dir)`` reads ``<results_dir>/beam_truth/modes.csv`` (``gomu run
studies/beam_truth.yaml``) and ``<results_dir>/beam_damage/{comparison,lcurve_choice,
damage_indices}.csv`` (``gomu run studies/beam_damage.yaml``) and returns one dict per item
(frequencies, SOO, MOO, regularized, L-curve, damage indices) with keys ``study``,
``item``, ``source`` (the source's stated inputs, settings and numbers), ``ours`` (our
numbers, from the tables), ``choice`` ("source-given" or "our assumption: <reason>") and
``verdict``. A pure function of the tables: nothing is computed from a model here.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from framework.report.reproduction import missing

STUDY = "beam damage (SPEC 7)"
#: the 20-element truth's candidates of results/beam_truth (points of studies/beam_truth.yaml)
TRUTH_POINTS = {"state1": "e6_second_half", "state2": "e6_second_e3_second"}
SOURCE_FREQUENCIES = {"state1": "12.83, 51.78, 115.99, 206.04, 323.64 Hz",
                      "state2": "12.64, 51.07, 115.04, 204.71, 320.15 Hz"}


#: the tables the rows need (relative to the results folder)
TABLES = ("beam_truth/modes.csv", "beam_damage/comparison.csv", "beam_damage/lcurve_choice.csv",
          "beam_damage/damage_indices.csv", "beam_damage/lcurve.csv")
ITEMS = ("frequencies (truth)", "SOO (baseline difference)", "SOO independent updates (ours)", "MOO (NSGA-II)",
         "regularized (PSO + Tikhonov)", "L-curve", "damage indices")


def _errors(cmp: pd.DataFrame, method: str) -> str:
    """'noise a %: mean/max |error| s1 x/y, s2 x/y' per noise level, from comparison.csv."""
    parts = []
    d = cmp[(cmp["method"] == method) & (cmp["measured_mesh"] == "truth")]
    for noise in sorted(set(d["noise_pct"])):
        cells = []
        for state in ("state1", "state2"):
            row = d[(d["noise_pct"] == noise) & (d["state"] == state)]
            if len(row):
                r = row.iloc[0]
                cells.append(f"{state} {r['mean_error']:.3f}/{r['max_error']:.3f}")
        seeds = int(d[d["noise_pct"] == noise]["seeds"].min())
        parts.append(f"{noise:g} % noise ({seeds} seeds): " + ", ".join(cells))
    return "mean/max |ratio error|: " + "; ".join(parts) if parts else "no runs"


def _best(cmp: pd.DataFrame, noise: float, methods: list[str]) -> str:
    d = cmp[(cmp["noise_pct"] == noise) & (cmp["measured_mesh"] == "truth") & cmp["method"].isin(methods)
            & cmp["state"].isin(["state1", "state2"])]
    if d.empty:
        return "n/a"
    mean = d.groupby("method")["mean_error"].mean().sort_values()
    return f"{mean.index[0]} ({mean.iloc[0]:.3f})"


def _legs(lcurve: pd.DataFrame) -> str:
    """Median over seeds and states of how far each leg of the L-curve runs (from the tables)."""
    legs = []
    for _, g in lcurve.groupby(["run_id", "state"]):
        g = g.sort_values("tau")
        c = g[g["chosen"].astype(bool)].iloc[0]
        legs.append((g["solution_norm"].iloc[0] / c["solution_norm"], g["residual_norm"].iloc[-1] / c["residual_norm"],
                     g["solution_norm"].iloc[-1] / c["solution_norm"]))
    if not legs:
        return ""
    a, b, c = (float(pd.Series(v).median()) for v in zip(*legs))
    return (f"Median over seeds: from the smallest tau to the corner the solution norm changes by a factor "
            f"{a:.2f} only (no steep norm-dominated leg: the unregularized fit is not noise-dominated); above the "
            f"corner the residual rises {b:.0f}-fold while the norm falls to {c:.1e} of its corner value (the "
            f"fit-dominated leg, ending on the initial model)")


def _change(cmp: pd.DataFrame) -> str:
    """Mean error of pso_tikhonov+sm (ours) minus pso+sm (ours), per noise level and state."""
    d = cmp[(cmp["measured_mesh"] == "truth") & cmp["state"].isin(["state1", "state2"])]
    d = d.set_index(["noise_pct", "state", "method"])["mean_error"]
    parts = []
    for noise, state in sorted({(n, s) for n, s, _ in d.index}):
        try:
            delta = d[(noise, state, "pso_tikhonov+sm (ours)")] - d[(noise, state, "pso+sm (ours)")]
        except KeyError:
            continue
        parts.append(f"{noise:g} % {state} {delta:+.4f}")
    return ", ".join(parts) or "n/a"


def rows(results_dir: Path) -> list[dict]:
    results_dir = Path(results_dir)
    absent = [t for t in TABLES if not (results_dir / t).is_file()]
    if absent:  # a study not run: one "not run" row per item
        return [missing(STUDY, item, "", absent[0]) for item in ITEMS]
    modes, cmp, choice, di, lcurve = (pd.read_csv(results_dir / t) for t in TABLES)
    out: list[dict] = []

    # frequencies of the 20-element truth
    err = modes.assign(abs_err=modes["error_pct"].abs()).groupby(["variant", "label"])["abs_err"].max()
    ours_truth = ", ".join(f"{state}: max {err[(state, label)]:.3f} %" for state, label in TRUTH_POINTS.items())
    others = err.drop([(s, lab) for s, lab in TRUTH_POINTS.items()])
    out.append({
        "study": STUDY, "item": "frequencies (truth)",
        "source": f"20-element truth, state 1: {SOURCE_FREQUENCIES['state1']}; state 2: {SOURCE_FREQUENCIES['state2']}",
        "ours": f"damage in the second halves (20-element elements 12 and 6): {ours_truth}; other halves miss by "
                f"{others.min():.2f}-{others.max():.2f} %",
        "choice": "our assumption: the SPEC leaves the damaged half open; chosen as the only halves that reproduce "
                  "the source's damaged frequencies",
        "verdict": "reproduced within 0.05 %" if max(err[(s, lab)] for s, lab in TRUTH_POINTS.items()) < 0.05
        else "not reproduced within 0.05 %",
    })
    budget = "PSO swarm 20 up to 50 000 evaluations per update, 20 noise seeds, shape noise a = 3 % (SPEC 7)"
    out.append({
        "study": STUDY, "item": "SOO (baseline difference)",
        "source": f"update the intact state (baseline), then each damaged state; severity = difference of the "
                  f"updated stiffness ratios; {budget}",
        "ours": f"soo (PSO): {_errors(cmp, 'soo')}. soo+sm (ours, each PSO result polished): "
                f"{_errors(cmp, 'soo+sm (ours)')}",
        "choice": "source-given (procedure, budget, noise model); our assumption: the evaluation budget alone ends "
                  "PSO (Pi of 1e-9..1e-4 lies below the 1e-6 target and 1e-8 stall tolerance of SPEC 3)",
        "verdict": "no number stated in the SPEC; best mean error at 3 % noise among the source's methods: "
                   + _best(cmp, 3.0, ["soo", "nsga2", "pso_tikhonov"]),
    })
    out.append({
        "study": STUDY, "item": "SOO independent updates (ours)",
        "source": "(not in the source: each damaged state updated against the initial model)",
        "ours": f"pso (ours): {_errors(cmp, 'pso (ours)')}. pso+sm (ours): {_errors(cmp, 'pso+sm (ours)')}",
        "choice": "our assumption: variant kept to show what the baseline difference removes (the discretization "
                  "error of the 10-element model)",
        "verdict": "our variant",
    })
    out.append({
        "study": STUDY, "item": "MOO (NSGA-II)",
        "source": "NSGA-II on both states at once (20 parameters, objectives Pi_1, Pi_2), population 500, "
                  "200 generations (100 000 evaluations), crossover 0.8; solution nearest the ideal point",
        "ours": f"nsga2: {_errors(cmp, 'nsga2')}. nsga2+sm (ours): {_errors(cmp, 'nsga2+sm (ours)')}",
        "choice": "source-given (population, generations, crossover, selection); a two-state point counts as 2 "
                  "model evaluations",
        "verdict": "no number stated in the SPEC",
    })
    taus = choice[choice["measured_mesh"] == "truth"] if "measured_mesh" in choice else choice
    out.append({
        "study": STUDY, "item": "regularized (PSO + Tikhonov)",
        "source": "PSO on Pi + tau ||x - x0||^2 towards the initial model, tau from the L-curve",
        "ours": f"pso_tikhonov: {_errors(cmp, 'pso_tikhonov')}. pso_tikhonov+sm (ours): "
                f"{_errors(cmp, 'pso_tikhonov+sm (ours)')}",
        "choice": "source-given (method, x0 = initial model); our assumption: x as I ratios (||r - 1||)",
        "verdict": "no number stated in the SPEC",
    })
    med = taus.groupby(["noise_pct", "state"])["tau"].agg(["median", "min", "max"])
    tau_text = "; ".join(f"{n:g} % {s}: median {r['median']:.1e} ({r['min']:.0e}..{r['max']:.0e})"
                         for (n, s), r in med.iterrows())
    out.append({
        "study": STUDY, "item": "L-curve",
        "source": "fit term against solution norm over a sweep of tau; corner chosen",
        "ours": f"residual norm sqrt(Pi) vs ||r - 1|| (log-log) over tau {lcurve['tau'].min():.0e}.."
                f"{lcurve['tau'].max():.0e}; corner by maximum curvature (Hansen); chosen tau per seed: {tau_text}. "
                f"{_legs(lcurve)}",
        "choice": "our assumption: the curve traced by sensitivity-method continuation over tau (a PSO per tau "
                  "would cost 50 000 evaluations each); Hansen's curvature rule (the source names no rule)",
        "verdict": f"corner found on every seed; Tikhonov at the corner changes the polished estimate's mean error "
                   f"by {_change(cmp)}",
    })
    d = di[(di["measured_mesh"] == "truth") & (di["truth_damage_index"] > 0)]
    parts = []
    for method in ("soo", "nsga2", "pso_tikhonov"):
        dm = d[(d["method"] == method) & (d["noise_pct"] == d["noise_pct"].max())]
        if len(dm):
            parts.append(method + ": " + ", ".join(
                f"{r['state']} e{int(r['element'])} {r['mean_damage_index']:.3f} (true {r['truth_damage_index']:.2f}, "
                f"detected {100 * r['detection_rate']:.0f} %)" for _, r in dm.iterrows()))
    fd = cmp[(cmp["measured_mesh"] == "truth") & cmp["method"].isin(["soo", "nsga2", "pso_tikhonov"])
             & cmp["state"].isin(["state1", "state2"])]
    fd_text = "; ".join(f"{m} {int(g['false_detections'].sum())}" for m, g in fd.groupby("method"))
    out.append({
        "study": STUDY, "item": "damage indices",
        "source": "damage index per element, false detections (undamaged elements reported damaged)",
        "ours": f"at {d['noise_pct'].max() if len(d) else float('nan'):g} % noise, damaged elements: "
                + "; ".join(parts) + f". False detections (all noise levels, seeds, both states): {fd_text}",
        "choice": "our assumption: damage index 1 - r, detection threshold 0.05 (the SPEC gives none)",
        "verdict": "no number stated in the SPEC",
    })
    return out
