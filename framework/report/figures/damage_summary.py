"""Figures of the ``damage_summary`` analysis (:mod:`framework.report.analyses.damage_summary`)
of a ``damage`` study, drawn from its ``damage_indices`` table and the run tables ``pareto``
and ``lcurve``, per noise level (measured mesh "truth"):

- ``damage_index_noise<n>.png``: damage index 1 - r per element and method (mean, bar = 1 sd
  over seeds), the truth and the detection threshold, one panel per damaged state;
- ``pareto_noise<n>.png``: NSGA-II's final Pareto front of the first seed and the point
  nearest the ideal point;
- ``lcurve_noise<n>.png``: the L-curves of the first seed, the corner of maximum curvature marked.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from framework.report.figures.style import save_figure, styled, subplots


def damage_figures(damage_indices: pd.DataFrame, pareto: pd.DataFrame | None, lcurve: pd.DataFrame | None,
                   out_dir: Path, threshold: float, levels: list[float]) -> list[Path]:
    """The figures of each noise level in ``levels`` that the tables hold; returns the files."""
    paths: list[Path] = []
    for noise in levels:
        d = damage_indices[(damage_indices["noise_pct"] == noise) & (damage_indices["measured_mesh"] == "truth")
                           & (damage_indices["state"] != "intact")]
        if d.empty:
            continue
        paths.append(damage_index_figure(d, out_dir / f"damage_index_noise{noise:g}.png", threshold, noise))
        if pareto is not None and not pareto.empty:
            p = pareto[(pareto["noise_pct"] == noise) & (pareto["measured_mesh"] == "truth")]
            if len(p):
                paths.append(pareto_figure(p, out_dir / f"pareto_noise{noise:g}.png", noise))
        if lcurve is not None and not lcurve.empty:
            c = lcurve[(lcurve["noise_pct"] == noise) & (lcurve["measured_mesh"] == "truth")]
            if len(c):
                paths.append(lcurve_figure(c, out_dir / f"lcurve_noise{noise:g}.png", noise))
    return paths


@styled
def damage_index_figure(d: pd.DataFrame, path: Path, threshold: float, noise: float) -> Path:
    methods = sorted(set(d["method"]))
    fig, axes = subplots(2, 1, figsize=(12, 8), sharex=True)
    width = 0.8 / max(len(methods), 1)
    for ax, state in zip(axes, ("state1", "state2")):
        ds = d[d["state"] == state]
        for k, method in enumerate(methods):
            dm = ds[ds["method"] == method].sort_values("element")
            ax.bar(dm["element"] - 0.4 + (k + 0.5) * width, dm["mean_damage_index"], width,
                   yerr=dm["sd_damage_index"], label=method, capsize=1, error_kw={"lw": 0.6})
        truth = ds.drop_duplicates("element").sort_values("element")
        ax.scatter(truth["element"], truth["truth_damage_index"], marker="_", s=600, color="k", zorder=5,
                   label="truth")
        ax.axhline(threshold, ls="--", color="grey", lw=1, label="threshold")
        ax.set_title(f"{state}, {noise:g} % shape noise: damage index 1 - r (mean, bar = 1 sd over seeds)")
        ax.set_ylabel("damage index")
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    axes[-1].set_xlabel("element")
    fig.tight_layout()
    return save_figure(fig, path)


@styled
def pareto_figure(p: pd.DataFrame, path: Path, noise: float) -> Path:
    seed = int(p["seed"].min())
    p = p[p["seed"] == seed]
    fig, ax = subplots(figsize=(5, 4))
    ax.scatter(p["Pi_state1"], p["Pi_state2"], s=10, label="final Pareto front")
    c = p[p["chosen"].astype(bool)]
    ax.scatter(c["Pi_state1"], c["Pi_state2"], s=80, color="r", marker="*", label="nearest ideal point")
    ax.set_xscale("log"), ax.set_yscale("log")
    ax.set_xlabel("Pi state 1"), ax.set_ylabel("Pi state 2")
    ax.set_title(f"NSGA-II, seed {seed}, {noise:g} % noise")
    ax.legend()
    fig.tight_layout()
    return save_figure(fig, path)


@styled
def lcurve_figure(c: pd.DataFrame, path: Path, noise: float) -> Path:
    seed = int(c["seed"].min())
    fig, axes = subplots(1, 2, figsize=(10, 4))
    for ax, state in zip(axes, ("state1", "state2")):
        d = c[(c["seed"] == seed) & (c["state"] == state)].sort_values("tau")
        ax.loglog(d["residual_norm"], d["solution_norm"], "o-", ms=3)
        for _, row in d.iloc[:: 4].iterrows():
            ax.annotate(f"{row['tau']:.0e}", (row["residual_norm"], row["solution_norm"]), fontsize=6)
        k = d[d["chosen"].astype(bool)]
        if len(k):
            ax.loglog(k["residual_norm"], k["solution_norm"], "r*", ms=14,
                      label=f"max curvature, tau={k['tau'].iloc[0]:.1e}")
            ax.legend()
        ax.set_xlabel("residual norm ||r|| = sqrt(Pi)")
        ax.set_ylabel("solution norm ||r_I - 1||")
        ax.set_title(f"L-curve {state}, seed {seed}, {noise:g} % noise")
    fig.tight_layout()
    return save_figure(fig, path)
