"""Reproduction rows of the laboratory frame (SPEC 5): identification, initial model and
torsion congruence, parameter selection, updated parameters / frequencies / MAC, added-mass
validation, timing, detailed frame. Every number is read from the tables under results/."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from framework.report.reproduction import fmt, fmt_list, missing, read_table

LAB = "Laboratory frame (3-DOF model)"
DETAILED = "Laboratory frame (detailed OpenSees model)"
MEASURED_HZ = {"base": (3.58, 5.01, 7.28), "mass_0.654kg": (3.54, 4.90, 7.21), "mass_1.379kg": (3.48, 4.79, 7.10)}
REPLICATION = ("pso", "ga", "annealing", "sm_initial", "sm_random")


def rows(results_dir: Path) -> list[dict]:
    out: list[dict] = []
    for part in (_identification, _initial_model, _selection, _algorithms, _updated, _validation, _timing,
                 _detailed):
        out += part(Path(results_dir))
    return out


# ---- identification ----------------------------------------------------------------------
def _identification(results: Path) -> list[dict]:
    source = ("input-output subspace identification, mean of 3 sweep tests: 3.58 / 5.01 / 7.28 Hz, "
              "damping 1.21 / 0.78 / 0.81 %; FRF peak picking 3.56 / 5.02 / 7.37 Hz")
    modes = read_table(results, "identification/modes.csv")
    if modes is None:
        return [missing(LAB, "identification", source, "identification/modes.csv")]
    lab = modes[modes["structure"] == "lab_frame"]
    n4 = lab[(lab["method"] == "n4sid") & (lab["record"] == "mean")].sort_values("mode")
    pp = lab[lab["method"] == "peak_picking"].sort_values("mode")
    ours = (f"simulated sweeps of a 'true' 3-DOF frame ({fmt_list(n4['f_true_hz'], 4)} Hz): N4SID mean of 3 "
            f"{fmt_list(n4['f_identified_hz'], 5)} Hz (max |error| {fmt(n4['f_error_pct'].abs().max(), 2)} %), "
            f"damping {fmt_list(100 * n4['zeta_identified'], 3)} %, min MAC to true "
            f"{fmt(n4['mac_to_true'].min(), 6)}; peak picking max |error| {fmt(pp['f_error_pct'].abs().max(), 2)} %, "
            f"damping error up to {fmt(pp['zeta_error_pct'].abs().max(), 3)} %")
    return [{"study": LAB, "item": "identification (results/identification)", "source": source, "ours": ours,
             "choice": "our assumption: no raw records are published, so the tests are simulated on the model "
                       "with the measured damping and 2 % sensor noise (SPEC 8)",
             "verdict": "the simulated modes are recovered (SPEC 8 asks for it)"}]


# ---- initial model and torsion congruence ---------------------------------------------------
def _initial_model(results: Path) -> list[dict]:
    source_f = "initial model about 3.58, 5.42, 7.85 Hz (kyy 8904, kxx 20294, kxy 0 N/m, krr 3067.8 N m, ex = ey = 0)"
    source_mac = "initial MACs 0.989, 0.974, 0.999 (modes 1-3); minimum of the updating about 1.3e-6"
    table = read_table(results, "lab_frame_congruence/congruence.csv")
    modes = read_table(results, "lab_frame_congruence/modes.csv")
    if table is None or modes is None:
        return [missing(LAB, "initial model, torsion congruence", source_mac, "lab_frame_congruence/congruence.csv")]
    chosen = table[table["chosen"].astype(bool)].iloc[0]
    init = modes[(modes["label"] == "initial_model") & (modes["variant"] == chosen["congruence"])
                 & (modes["case"] == "base")].sort_values("mode")
    out = [{"study": LAB, "item": "initial model frequencies", "source": source_f,
            "ours": f"{fmt_list(init['f_model_hz'], 4)} Hz", "choice": "source-given (all inputs)",
            "verdict": _verdict(np.allclose(init["f_model_hz"], (3.58, 5.42, 7.85), rtol=0.005),
                                "within 0.5 %", "differs by more than 0.5 %")}]
    for _, r in table.iterrows():
        macs = fmt_list([r["mac_1"], r["mac_2"], r["mac_3"]], 4)
        ours = (f"reading '{r['congruence']}': initial MACs {macs}, minimum {fmt(r['minimum_objective'], 4)} "
                f"(MAC RMS difference {fmt(r['mac_rms_diff'], 2)}, "
                f"minimum off by 10^{fmt(r['minimum_misfit_log10'], 2)}, "
                f"score {fmt(r['score'], 3)})")
        chosen_row = bool(r["chosen"])
        out.append({
            "study": LAB, "item": f"torsion congruence T = diag(1, 1, b/2): {r['congruence']}",
            "source": source_mac, "ours": ours,
            "choice": ("our assumption, the default: published torsion column divided by b/2 against the model "
                       "rotation; lowest score = RMS(dMAC)/0.01 + |log10(min/1.3e-6)| "
                       "(framework/report/analyses/congruence.py)") if chosen_row else
                      "our alternative reading (option congruence of the lab frame)",
            "verdict": ("closest to the source (no reading reproduces its mode-2 MAC 0.974)" if chosen_row
                        else "further from the source"),
        })
    return out


def _verdict(ok: bool, yes: str, no: str) -> str:
    return yes if ok else no


# ---- parameter selection -----------------------------------------------------------------
SELECTION = {
    "pso_swarm": ("PSO swarm size 5, 10, 20, 40, 50, 100 (factor 1), 10 runs each; converged when the mean best "
                  "of 10 runs < 1e-5", "source chose swarm 20"),
    "pso_factor": ("PSO factor on (gamma, c1, c2) 0.5, 0.75, 0.9, 1, 1.25, 1.5 (swarm 20); same rule",
                   "source chose factor 0.75"),
    "ga": ("GA population 20: roulette + single point 0.8; tournament + single / two point / scattered 0.8; "
           "tournament + two point 0.7, 0.25, 1.0 without mutation; same rule",
           "source chose tournament, two point, 0.7"),
    "annealing": ("SiA: Boltzmann vs exponential schedule; initial temperature and re-anneal interval 25, 75, 100, "
                  "200, 500, 1000; same rule", "source chose T0 = re-anneal interval = 200"),
}


def _selection(results: Path) -> list[dict]:
    out = []
    for name, (source, chosen) in SELECTION.items():
        rel = f"selection/{name}/convergence_summary.csv"
        t = read_table(results, rel)
        if t is None:
            out.append(missing(LAB, f"parameter selection: {name}", source, rel))
            continue
        if "converged_absolute" not in t:  # a table from before issue 15
            out.append({"study": LAB, "item": f"parameter selection: {name}", "source": source,
                        "ours": f"not regenerated: results/{rel} predates issue 15 (torsion congruence 'model', "
                                f"relative rule only; {int(t['converged'].sum())} of {len(t)} settings converged "
                                "by it); its config has since changed",
                        "choice": "", "verdict": "not run with the faithful settings"})
            continue
        t = t.assign(setting=[_setting(lab, var) for lab, var in zip(t["label"], t["variant"])])
        parts = []
        for _, r in t.iterrows():
            evals = f", {fmt(r['mean_evaluations_to_absolute'], 4)} evaluations" if r["converged_absolute"] else ""
            parts.append(f"{r['setting']}: mean best {fmt(r['mean_best'], 3)}, "
                         f"{'converged' if r['converged_absolute'] else 'not converged'} (absolute"
                         + evals
                         + f"; {int(r['runs_reaching_absolute'])}/{int(r['runs'])} runs below 1e-5)"
                         + f" / {'converged' if r['converged'] else 'not converged'} (relative)")
        n_abs, n_rel = int(t["converged_absolute"].sum()), int(t["converged"].sum())
        ours = (f"absolute rule: {n_abs} of {len(t)} settings converged, relative rule (within 1e-5 of "
                f"f* = {fmt(t['f_star'].iloc[0], 4)}): {n_rel}. " + "; ".join(parts))
        choice = "source-given settings, 10 runs, 50 000 evaluations, 10-iteration window"
        if name == "ga":
            choice += ("; GA crossover fraction with the toolbox meaning (2 elite children: our assumption); "
                       + _ga_mutation(read_table(results, "selection/ga/runs.csv")))
        if name == "annealing":
            choice = ("our assumption: pure dual_annealing (no local search); schedule -> visiting parameter "
                      "(exponential 2.62, Boltzmann 1.5), re-anneal interval -> restart_temp_ratio; T0 and the "
                      "interval varied together (our reading; it also fitted our compute)")
        out.append({"study": LAB, "item": f"parameter selection: {name}", "source": source, "ours": ours,
                    "choice": choice, "verdict": chosen + _chosen_verdict(name, t)})
    return out


def _setting(label: str, variant: str) -> str:
    return label if variant == "default" else (variant if label in ("pso",) else f"{label} {variant}")


def _chosen_verdict(name: str, t) -> str:
    key = {"pso_swarm": "swarm_size=20", "pso_factor": "factor=0.75", "ga": "tournament_two_point_0.7",
           "annealing": "schedule_exponential"}[name]
    hit = t[t["setting"].str.contains(key, regex=False)]
    if hit.empty:
        return ""
    return "; it converges by the absolute rule" if bool(hit["converged_absolute"].iloc[0]) else \
        "; it does not converge by the absolute rule here"


# ---- updating: algorithms, parameters, frequencies and MAC ---------------------------------
def _algorithms(results: Path) -> list[dict]:
    runs = read_table(results, "lab_frame/runs.csv")
    source = ("10 runs per algorithm; termination: best improved < 1e-8 over 10 iterations, best < 1e-6, or "
              "50 000 evaluations; PSO swarm 20, factor 0.75; GA population 20, tournament, two point, "
              "fraction 0.7, mutation 0.01, elitism; SiA T0 200, re-anneal 200; SM pseudo-inverse")
    if runs is None:
        return [missing(LAB, "updating algorithms", source, "lab_frame/runs.csv")]
    out = []
    for label, g in runs.groupby("label", sort=False):
        ours = (f"{label}: {len(g)} runs, best objective median {fmt(g['objective'].median(), 4)} "
                f"(min {fmt(g['objective'].min(), 4)}, max {fmt(g['objective'].max(), 4)}), evaluations median "
                f"{fmt(g['n_evaluations'].median(), 5)}, status " +
                ", ".join(f"{k} {v}" for k, v in g["status"].value_counts().sort_index().items()))
        mine = "(ours)" in label
        out.append({"study": LAB, "item": f"updating: {label}", "source": "" if mine else source, "ours": ours,
                    "choice": _algorithm_choice(label) + ("; " + _ga_mutation(g) if label == "ga" else ""),
                    "verdict": ""})
    return out


def _ga_mutation(runs) -> str:
    """The GA mutation reading of a runs table (tables from before issue 27 have no column: uniform)."""
    col = runs["mutation"].dropna().unique() if runs is not None and "mutation" in runs else []
    reading = ", ".join(map(str, col)) or "uniform"
    if reading == "adaptive_feasible":
        return "mutation: the toolbox's adaptive feasible, its default for a bounded problem (issue 27)"
    if reading == "uniform":
        return ("mutation: per-gene uniform reset at rate 0.01 (the reading before issue 27, which cannot refine "
                "a minimum; the replication now uses adaptive feasible)")
    return f"mutation: {reading}"


def _algorithm_choice(label: str) -> str:
    return {
        "pso": "source-given settings (pyswarms-style loop; velocity clamp (upper-lower)/2, boundary reset)",
        "ga": "source-given; toolbox meaning of the crossover fraction: 2 elite, 13 crossover, 5 mutation "
              "children (elite count 2: our assumption)",
        "annealing": "our mapping of SiA to scipy dual_annealing without local search "
                     "(framework/optimizers/annealing.py)",
        "sm_initial": "source-given SM from the initial point (scipy least_squares on the residual vector)",
        "sm_random": "SM from random starts (our addition: the source starts at the initial point)",
        "pso_stall100 (ours)": "ours: 100-iteration window instead of 10",
        "ga_stall100 (ours)": "ours: 100-iteration window instead of 10",
        "annealing_local_search (ours)": "ours: dual_annealing with its L-BFGS-B local search (a hybrid)",
        "hybrid_pso_sm (ours)": "ours: PSO 2 000 evaluations, then SM from 3 distinct best points",
    }.get(label, "ours" if "(ours)" in label else "")


def _best_runs(runs):
    return runs.loc[runs.groupby("label", sort=False)["objective"].idxmin()]


def _updated(results: Path) -> list[dict]:
    runs = read_table(results, "lab_frame/runs.csv")
    params = read_table(results, "lab_frame/parameters.csv")
    modes = read_table(results, "lab_frame/modes.csv")
    source = ("updated kyy [7000, 10600], kxx [16000, 24500], kxy [-500, 500] N/m, krr [2500, 3500] N m, "
              "ex, ey [-0.1, 0.1] m to the measured 3.58 / 5.01 / 7.28 Hz and shapes (Pi = Pi_f + Pi_MAC)")
    if runs is None or params is None or modes is None:
        return [missing(LAB, "updated parameters", source, "lab_frame/parameters.csv")]
    best = runs.loc[runs["objective"].idxmin()]
    p = params[params["run_id"] == best["run_id"]].set_index("parameter")
    names = ["kyy", "kxx", "kxy", "krr", "ex", "ey"]
    values = ", ".join(f"{n} {fmt(p.loc[n, 'value'], 5)} {p.loc[n, 'unit']}" for n in names if n in p.index)
    out = [{"study": LAB, "item": "updated parameters (best run of all)",
            "source": source,
            "ours": f"{best['label']} seed {int(best['seed'])}: {values}; Pi = {fmt(best['objective'], 4)}",
            "choice": "source-given parameters and bounds; torsion congruence 'measured' (our assumption)",
            "verdict": ""}]
    spread = params[params["label"] == "pso"].groupby("parameter")["value"].agg(["min", "max"])
    if not spread.empty:
        out[0]["ours"] += "; PSO runs span " + ", ".join(
            f"{n} {fmt(spread.loc[n, 'min'], 4)}..{fmt(spread.loc[n, 'max'], 4)}" for n in names if n in spread.index)
    base = modes[modes["case"] == "base"]
    for _, b in _best_runs(runs[runs["label"].isin(REPLICATION) | runs["label"].str.contains("ours")]).iterrows():
        m = base[base["run_id"] == b["run_id"]].sort_values("mode")
        if m.empty:
            continue
        out.append({"study": LAB, "item": f"updated frequencies and MAC: {b['label']} (best run)",
                    "source": "measured 3.58 / 5.01 / 7.28 Hz",
                    "ours": f"{fmt_list(m['f_model_hz'], 4)} Hz (errors {fmt_list(m['error_pct'], 2)} %), "
                            f"MAC {fmt_list(m['mac'], 4)}",
                    "choice": "", "verdict": _verdict(bool((m["error_pct"].abs() < 0.5).all()),
                                                      "reproduces the measured frequencies within 0.5 %",
                                                      "misses a measured frequency by more than 0.5 %")})
    return out


# ---- added-mass validation ---------------------------------------------------------------
def _validation(results: Path) -> list[dict]:
    runs = read_table(results, "lab_frame/runs.csv")
    modes = read_table(results, "lab_frame/modes.csv")
    source = ("masses at the slab centre: 0.654 kg -> 3.54, 4.90, 7.21 Hz; 1.379 kg -> 3.48, 4.79, 7.10 Hz; "
              "the updated model with the mass must predict them (differences and MAC)")
    if runs is None or modes is None:
        return [missing(LAB, "added-mass validation", source, "lab_frame/modes.csv")]
    best = runs.loc[runs["objective"].idxmin()]
    m = modes[modes["run_id"] == best["run_id"]]
    out = []
    torsion = []
    for case in ("base", "mass_0.654kg", "mass_1.379kg"):
        c = m[m["case"] == case].sort_values("mode")
        torsion.append(c["f_model_hz"].iloc[2] if len(c) == 3 else np.nan)
        if case == "base" or c.empty:
            continue
        out.append({"study": LAB, "item": f"added-mass validation {case} (best run)", "source": source,
                    "ours": f"{fmt_list(c['f_model_hz'], 4)} Hz (errors {fmt_list(c['error_pct'], 2)} %), "
                            f"MAC {fmt_list(c['mac'], 4)}",
                    "choice": "our assumption: the mass is a compact steel cylinder (h = d; 47 mm for 0.654 kg, "
                              "61 mm for 1.379 kg) at the slab centre with its own polar inertia m d^2 / 8",
                    "verdict": _verdict(bool((c["error_pct"].abs() < 1.0).all()), "all within 1 %",
                                        f"max |error| {fmt(c['error_pct'].abs().max(), 2)} %")})
    out.append({"study": LAB, "item": "torsion frequency with the added masses",
                "source": "measured 7.28 -> 7.21 -> 7.10 Hz",
                "ours": f"{fmt_list(torsion, 5)} Hz",
                "choice": "our assumption (block size not tuned to the measured frequencies)",
                "verdict": "a compact block at the centre adds 0.01-0.05 % of J: it cannot explain the measured "
                           "1-2.5 % torsion drop (the masses' real size or position is not known)"})
    return out


# ---- timing ------------------------------------------------------------------------------
def _timing(results: Path) -> list[dict]:
    source = "each of PSO, GA, SiA run to 50 000 evaluations: 75.3, 76.25, 111.4 s on the source's machine"
    t = read_table(results, "lab_frame_timing/timing.csv")
    if t is None:
        return [missing(LAB, "timing", source, "lab_frame_timing/timing.csv")]
    parts = [f"{r['label']}: {fmt(r['mean_wall_s'], 3)} s for {int(r['mean_evaluations'])} evaluations "
             f"({fmt(r['ms_per_evaluation'], 3)} ms each; {fmt(r['ratio_to_source'], 2)} x the source)"
             for _, r in t.iterrows()]
    return [{"study": LAB, "item": "timing (50 000 evaluations)", "source": source, "ours": "; ".join(parts),
             "choice": "one point per call as the source's toolboxes; vectorized population calls are ours; "
                       "our machine is shared (2 cores, heavily loaded while measuring), so the absolute times "
                       "are not comparable with the source's; the ratios between our rows are",
             "verdict": ""}]


# ---- detailed frame ----------------------------------------------------------------------
def _detailed(results: Path) -> list[dict]:
    source_init = "initial detailed model about 3.58, 7.97, 10.29 Hz (modes 2 and 3 far too stiff)"
    sens = read_table(results, "lab_frame_detailed/sensitivity/modes.csv")
    comp = read_table(results, "lab_frame_detailed/updating/comparison.csv")
    out = []
    if sens is None:
        out.append(missing(DETAILED, "initial model", source_init, "lab_frame_detailed/sensitivity/modes.csv"))
    else:
        s = sens[(sens["label"] == "initial") & (sens["variant"] == "detailed") & (sens["case"] == "base")
                 & (sens["pairing"] == "objective")].sort_values("mode")
        out.append({"study": DETAILED, "item": "initial model", "source": source_init,
                    "ours": f"{fmt_list(s['f_model_hz'], 4)} Hz, MAC {fmt_list(s['mac'], 4)}",
                    "choice": "our assumptions: column axes 30 mm inside the slab edges, bracket axes, nonstructural "
                              "mass spread (framework/structures/lab_frame/detailed.py)",
                    "verdict": _verdict(bool(np.allclose(s["f_model_hz"], (3.58, 7.97, 10.29), rtol=0.05)),
                                        "within 5 % of the source's initial model", "more than 5 % off")})
    source_upd = "k_r2 and k_r3 updated (the only parameters sensitive to modes 1-3); validation with the added masses"
    if comp is None:
        out.append(missing(DETAILED, "updated model", source_upd, "lab_frame_detailed/updating/comparison.csv"))
        return out
    for case in ("base", "mass_0.654kg", "mass_1.379kg"):
        for model in ("detailed", "3dof"):
            c = comp[(comp["model"] == model) & (comp["case"] == case)].sort_values("mode")
            if c.empty:
                continue
            out.append({"study": DETAILED, "item": f"updated {model} model, {case}", "source": source_upd
                        + f"; measured {fmt_list(MEASURED_HZ[case], 3)} Hz",
                        "ours": f"{fmt_list(c['f_model_hz'], 4)} Hz (errors {fmt_list(c['error_pct'], 2)} %), "
                                f"MAC {fmt_list(c['mac'], 4)}",
                        "choice": "best run of PSO (10 runs) and SM; added masses as steel blocks (our assumption)",
                        "verdict": ""})
    return out
