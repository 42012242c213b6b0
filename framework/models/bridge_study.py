"""Bridge studies that are not plain optimizer runs (SPEC 6): tables and figures.

- :func:`initial_frequencies`: initial model (1, 2, 4, 8 elements per cable) next to the
  measured (subspace, peak picking) and the source's design-model frequencies;
- :func:`sensitivities`: relative sensitivities (0.1 % forward difference) of each paired
  frequency and MAC to the six parameters, singular values, condition number and the
  parameter correlation of the linearized fit;
- :func:`cable_models`: which measured modes the 1- and 4-element cable models reproduce
  (MAC pairing against the reference shapes), initially and after SM updating;
- :func:`summarize_updating`: SM agreement between starts, PSO spread over runs and the
  SNT minima, read from the study runner's tidy tables (``gomu run studies/bridge.yaml``).

Every function returns a tidy pandas DataFrame and writes it (CSV) with its figure under
``out_dir``. Figures are drawn from the tables only.
"""

from __future__ import annotations

import json
import logging
from pathlib import Path

import numpy as np
import pandas as pd

from framework.io import atomic_write_text, save_figure
from framework.models import bridge
from framework.objectives import ObjectiveSpec, RatioConstraint
from framework.optimizers import Budget, run_optimizer
from framework.problem import UpdatingProblem

log = logging.getLogger(__name__)

#: objective of every bridge study (see studies/bridge.yaml)
SPEC = ObjectiveSpec(frequency_window=0.25, ratio_constraints=(RatioConstraint("K_t_deck", "K_bearing", 2e-4),))


def bridge_problem(cable_elements: int = 4, **options) -> UpdatingProblem:
    """Updating problem of the bridge with the study objective (fast path)."""
    model = bridge.make_model(cable_elements, fast=True, **options)
    return UpdatingProblem(model, bridge.measured("base"), objective=SPEC, name=f"bridge_{cable_elements}el")


def _write(df: pd.DataFrame, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(path, df.to_csv(index=False))
    return path


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


NOTES = """Bridge study outputs (SPEC 6). Measured mode shapes of the bridge are not published:
every MAC here compares the model with REFERENCE shapes, the initial 4-element model's
deck modes (paired with the measured modes by type and nearest frequency) at 36 edge
sensor DOFs (uz, uy at both edges of 9 stations). The MAC term therefore only guards
mode identity; the frequencies are the measured (subspace) ones.
Objective: Pi_f + Pi_MAC + 0.0002 |K_t_deck/K_bearing - 1|, MAC pairing within +-25 %.
Model and choices: docs/bridge.md. Optimizer runs: updating/ (gomu run studies/bridge.yaml).
"""


def write_notes(out_dir: Path) -> Path:
    """NOTES.txt stating where the reference shapes come from."""
    path = out_dir / "NOTES.txt"
    atomic_write_text(path, NOTES)
    return path


# --- (0) initial model ----------------------------------------------------------------
def initial_frequencies(out_dir: Path, cable_elements=(1, 2, 4, 8)) -> pd.DataFrame:
    """One row per cable discretisation and measured mode (paired by type and frequency)."""
    rows = []
    for n in cable_elements:
        result = bridge.make_model(n, fast=True).modal({})
        idx = bridge.pair_by_type(result)
        for j, i in enumerate(idx):
            f_model = float(result.frequencies_hz[i]) if i >= 0 else np.nan
            rows.append(
                {
                    "cable_elements": n,
                    "mode": j + 1,
                    "label": bridge.MEASURED_LABELS[j],
                    "type": bridge.MEASURED_TYPES[j],
                    "f_measured_hz": bridge.MEASURED_HZ[j],
                    "f_peak_hz": bridge.MEASURED_PEAK_HZ[j],
                    "f_design_model_hz": bridge.DESIGN_MODEL_HZ[j],
                    "f_model_hz": f_model,
                    "error_pct": 100.0 * (f_model / bridge.MEASURED_HZ[j] - 1.0),
                    "deck_energy": float(result.mode_info["deck_energy"][i]) if i >= 0 else np.nan,
                    "cable_energy": float(result.mode_info["cable_energy"][i]) if i >= 0 else np.nan,
                }
            )
    df = pd.DataFrame(rows)
    _write(df, out_dir / "initial_frequencies.csv")
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 4))
    four = df[df.cable_elements == 4]
    x = four["mode"].to_numpy()
    ax.plot(x, four.f_measured_hz, "ko", label="measured (subspace)")
    ax.plot(x, four.f_design_model_hz, "s", mfc="none", label="source design model")
    for n, g in df.groupby("cable_elements"):
        ax.plot(g["mode"], g.f_model_hz, "x", label=f"this model, {n} el./cable")
    ax.set_xlabel("measured mode")
    ax.set_ylabel("frequency (Hz)")
    ax.set_xticks(x)
    ax.legend(fontsize=8)
    ax.set_title("Bridge: initial model vs measured")
    fig.tight_layout()
    save_figure(fig, out_dir / "initial_frequencies.png", dpi=120, tight=False)
    return df


# --- (1) sensitivities ------------------------------------------------------------------
def sensitivities(out_dir: Path, problem: UpdatingProblem | None = None) -> pd.DataFrame:
    """Tidy sensitivity table at the initial point and at the SM-updated point.

    At the initial point the reference shapes are the model's own, so every MAC is 1, at
    its maximum, and its first derivative vanishes; the MAC sensitivities are therefore
    also given at the SM-updated point (start 1.00). Also writes singular values,
    condition numbers, the parameter correlation and bar charts.
    """
    from framework.sensitivity import sensitivity_matrix

    problem = problem or bridge_problem()
    updated = run_optimizer("sm", problem, 0, Budget(max_evaluations=800), start_factor=1.0)
    points = {"initial": problem.parameters.initial, "updated (SM)": updated.theta_best}
    tables, singular, corr = [], [], []
    for point, theta in points.items():
        res = sensitivity_matrix(problem, theta0=theta, rel_step=1e-3)
        tables.append(res.table().assign(point=point))
        singular.append(
            pd.DataFrame(
                {
                    "point": point,
                    "index": np.arange(1, res.singular_values.size + 1),
                    "singular_value": res.singular_values,
                    "condition_number": res.condition_number,
                }
            )
        )
        corr.append(res.correlation_table().reset_index(names="parameter").assign(point=point))
    table = pd.concat(tables, ignore_index=True)
    _write(table, out_dir / "sensitivity.csv")
    singular = pd.concat(singular, ignore_index=True)
    _write(singular, out_dir / "sensitivity_singular_values.csv")
    corr = pd.concat(corr, ignore_index=True)
    _write(corr, out_dir / "parameter_correlation.csv")
    _plot_sensitivities(table, singular, corr, out_dir)
    return table


def _plot_sensitivities(table, singular, corr, out_dir: Path) -> None:
    plt = _pyplot()
    import seaborn as sns

    panels = [("frequency", "initial"), ("mac", "updated (SM)")]
    fig, axes = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
    for ax, (quantity, point) in zip(axes, panels):
        sel = table[(table.quantity == quantity) & (table.point == point)]
        sns.barplot(data=sel, x="mode", y="sensitivity", hue="parameter", ax=ax)
        ax.set_ylabel(("df/f" if quantity == "frequency" else "dMAC") + " per dp/p")
        ax.axhline(0.0, color="k", lw=0.5)
        ax.legend(fontsize=7, ncol=3)
        cond = singular[singular.point == point].condition_number.iloc[0]
        ax.set_title(f"{quantity} sensitivities at the {point} point (condition number {cond:.1f})", fontsize=10)
    fig.tight_layout()
    save_figure(fig, out_dir / "sensitivity.png", dpi=120, tight=False)
    fig, ax = plt.subplots(figsize=(5.5, 4.5))
    c = corr[corr.point == "initial"].drop(columns="point").set_index("parameter")
    sns.heatmap(c, annot=True, fmt=".2f", vmin=-1, vmax=1, cmap="RdBu_r", ax=ax)
    ax.set_title("parameter correlation (linearized fit, initial point)", fontsize=10)
    fig.tight_layout()
    save_figure(fig, out_dir / "parameter_correlation.png", dpi=120, tight=False)


# --- (5) 1- vs 4-element cables ---------------------------------------------------------
def cable_models(out_dir: Path, cable_elements=(1, 4), budget: int = 800) -> pd.DataFrame:
    """Mode tables (MAC pairing) of each cable model, initial and after SM from 1.00."""
    frames = []
    for n in cable_elements:
        problem = bridge_problem(n)
        stages = [("initial", problem.parameters.initial, np.nan)]
        result = run_optimizer("sm", problem, 0, Budget(max_evaluations=budget), start_factor=1.0)
        stages.append(("updated (SM)", result.theta_best, result.objective))
        for stage, theta, objective in stages:
            table = problem.mode_table(theta)
            table.insert(0, "stage", stage)
            table.insert(0, "cable_elements", n)
            table["objective"] = (
                objective
                if stage != "initial"
                else float(problem.objective(problem.parameters.to_normalized(theta)[None, :])[0])
            )
            for name, ratio in zip(problem.parameters.names, problem.parameters.to_ratio(theta)):
                table[f"ratio_{name}"] = ratio
            frames.append(table)
    df = pd.concat(frames, ignore_index=True)
    _write(df, out_dir / "cable_models.csv")
    plt = _pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    for ax, (stage, g) in zip(axes, df.groupby("stage", sort=False)):
        for n, gg in g.groupby("cable_elements"):
            err = np.where(gg.matched, gg.error_pct, np.nan)
            ax.plot(gg["mode"], err, "o-", label=f"{n} el./cable")
            missing = gg["mode"][~gg.matched.astype(bool)]
            label = f"{n} el.: unmatched" if missing.size else None
            ax.plot(missing, np.zeros(missing.size), "rx", ms=12, mew=2, label=label)
        ax.axhline(0, color="k", lw=0.5)
        ax.set_title(stage)
        ax.set_xlabel("measured mode")
        ax.legend(fontsize=8)
    axes[0].set_ylabel("frequency error (%)")
    fig.tight_layout()
    save_figure(fig, out_dir / "cable_models.png", dpi=120, tight=False)
    return df


# --- (2)-(4) summaries of the optimizer runs ---------------------------------------------
def summarize_updating(runs_dir: Path, out_dir: Path) -> dict[str, pd.DataFrame]:
    """SM agreement, PSO spread and SNT minima from the runner's tables in ``runs_dir``."""
    runs = pd.read_csv(runs_dir / "runs.csv")
    params = pd.read_csv(runs_dir / "parameters.csv")
    modes = pd.read_csv(runs_dir / "modes.csv")
    out: dict[str, pd.DataFrame] = {}
    wide = params.pivot_table(index=["run_id", "label", "seed"], columns="parameter", values="ratio").reset_index()
    wide = wide.merge(runs[["run_id", "objective", "n_evaluations", "condition_number", "status"]], on="run_id")
    names = list(bridge.PARAMETER_NAMES)
    sm = wide[wide.label.str.startswith("sm")].sort_values("label")
    if not sm.empty:
        x = sm[names].to_numpy()
        sm = sm.assign(max_ratio_distance_between_starts=float(np.max(np.ptp(x, axis=0))))
        out["sm"] = _write_frame(sm, out_dir / "sm_starts.csv")
    pso = wide[wide.label == "pso"]
    if not pso.empty:
        spread = pso[names + ["objective"]].describe().T.reset_index(names="quantity")
        out["pso"] = _write_frame(spread, out_dir / "pso_spread.csv")
    extra_path = runs_dir / "extra.csv"
    if extra_path.exists():
        extra = pd.read_csv(extra_path)
        radius = {r.run_id: float(json.loads(r.value)) for r in extra[extra.key == "niche_radius"].itertuples()}
        rows = []
        for _, rec in extra[extra.key == "minima"].iterrows():
            r = radius.get(rec.run_id, np.nan)
            for m in json.loads(rec.value):
                nearest = min(m["distance_to_previous"], default=np.nan)
                ratios = np.asarray(m["theta"]) / 1.0  # parameters are ratios with initial 1
                rows.append(
                    {
                        "run_id": rec.run_id,
                        "minimum": m["minimum"],
                        **dict(zip(names, ratios)),
                        "raw_objective": m["raw_objective"],
                        "derated_objective": m["derated_objective"],
                        "artefact_of_niche_radius": m["artefact"],
                        "distance_to_previous": json.dumps([round(d, 4) for d in m["distance_to_previous"]]),
                        "niche_radius": r,
                        # G = 1 from d = r on, so the derated surface has a rim there:
                        # a minimum on the rim is an artefact even when raw == derated
                        "on_niche_boundary": bool(abs(nearest - r) < 0.01 * r),
                        "n_evaluations": m["n_evaluations"],
                    }
                )
        if rows:
            out["snt"] = _write_frame(pd.DataFrame(rows), out_dir / "snt_minima.csv")
    best = runs.loc[runs.objective.idxmin()]
    best_modes = modes[(modes.run_id == best.run_id) & (modes["case"] == "base")]
    out["best_modes"] = _write_frame(best_modes, out_dir / "updated_modes_best_run.csv")
    _plot_updated(wide, modes, out_dir)
    return out


def _write_frame(df: pd.DataFrame, path: Path) -> pd.DataFrame:
    _write(df, path)
    return df


def _plot_updated(wide: pd.DataFrame, modes: pd.DataFrame, out_dir: Path) -> None:
    plt = _pyplot()
    import seaborn as sns

    names = list(bridge.PARAMETER_NAMES)
    long = wide.melt(id_vars=["run_id", "label"], value_vars=names, var_name="parameter", value_name="ratio")
    long["method"] = long.label.where(~long.label.str.startswith("sm"), "sm")
    fig, ax = plt.subplots(figsize=(9, 4))
    sns.stripplot(data=long, x="parameter", y="ratio", hue="method", dodge=True, ax=ax)
    ax.axhline(1.0, color="k", lw=0.5)
    ax.set_ylim(0.55, 1.35)
    ax.set_title("Bridge: updated parameter ratios (bounds 0.6-1.3)")
    fig.tight_layout()
    save_figure(fig, out_dir / "updated_ratios.png", dpi=120, tight=False)
    base = modes[modes["case"] == "base"].copy()
    base["method"] = base.label.where(~base.label.str.startswith("sm"), "sm")
    fig, ax = plt.subplots(figsize=(9, 4))
    sns.stripplot(data=base, x="mode", y="error_pct", hue="method", dodge=True, ax=ax)
    ax.axhline(3.0, color="r", lw=0.5, ls="--")
    ax.axhline(-3.0, color="r", lw=0.5, ls="--")
    ax.set_ylabel("frequency error after updating (%)")
    ax.set_title("Bridge: updated vs measured frequencies (every run)")
    fig.tight_layout()
    save_figure(fig, out_dir / "updated_errors.png", dpi=120, tight=False)
