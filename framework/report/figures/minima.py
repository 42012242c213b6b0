"""Figures of the ``minima`` analysis (:mod:`framework.report.analyses.minima`), drawn from
the runs, parameters and minima tables (each row labelled with its ``method`` by the analysis).

- ``objective_distribution.png``: final objective per method, every run a point over a box plot;
- ``cost.png``: final objective and wall time against model evaluations;
- ``distinct_minima.png``: normalized parameters of the best distinct minima (parallel coordinates);
- ``alphas.png``: updated parameters per method, one point per run.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pandas as pd
import seaborn as sns

from framework.report.figures.style import save_figure, styled, subplots

log = logging.getLogger(__name__)


def minima_figures(runs: pd.DataFrame, parameters: pd.DataFrame, minima: pd.DataFrame, names: list[str],
                   out_dir: Path) -> list[Path]:
    """The four figures (a failing one is logged and skipped); ``runs``: the runs that did not
    fail; ``names``: the parameters in their natural order."""
    written = []
    for fn, args, fname in (
        (objectives_figure, (runs,), "objective_distribution.png"),
        (cost_figure, (runs,), "cost.png"),
        (minima_figure, (minima, names), "distinct_minima.png"),
        (alphas_figure, (parameters, names), "alphas.png"),
    ):
        try:
            written.append(fn(*args, out_dir / fname))
        except Exception as exc:  # a figure must not lose the tables
            log.warning("figure %s failed: %s", fname, exc)
    return written


@styled
def objectives_figure(runs: pd.DataFrame, path: Path) -> Path:
    order = runs.groupby("method")["objective"].median().sort_values().index.tolist()
    fig, ax = subplots(figsize=(7, 4.2))
    sns.boxplot(data=runs, x="method", y="objective", order=order, ax=ax, color="0.9", showfliers=False)
    sns.stripplot(data=runs, x="method", y="objective", order=order, ax=ax, size=4, alpha=0.7)
    ax.set(yscale="log", xlabel="", ylabel="final objective",
           title="Final objective, every run a point (box: quartiles; whiskers: 1.5 IQR)")
    ax.tick_params(axis="x", rotation=20)
    return save_figure(fig, path)


@styled
def cost_figure(runs: pd.DataFrame, path: Path) -> Path:
    fig, axes = subplots(1, 2, figsize=(11, 4.2))
    sns.scatterplot(data=runs, x="n_evaluations", y="objective", hue="method", ax=axes[0], alpha=0.8)
    axes[0].set(yscale="log", xlabel="model evaluations", ylabel="final objective", title="Objective vs. cost")
    sns.scatterplot(data=runs, x="n_evaluations", y="wall_s", hue="method", ax=axes[1], alpha=0.8, legend=False)
    axes[1].set(xlabel="model evaluations", ylabel="wall time [s]", title="Wall time vs. evaluations")
    axes[0].legend(fontsize=7)
    return save_figure(fig, path)


@styled
def minima_figure(minima: pd.DataFrame, names: list[str], path: Path, n_show: int = 8) -> Path:
    """Normalized parameters of the best distinct minima (parallel coordinates)."""
    top = minima.head(n_show)
    fig, ax = subplots(figsize=(max(7, 0.55 * len(names) + 2), 4.5))
    x = np.arange(len(names))
    for _, row in top.iterrows():
        ax.plot(
            x,
            row[names].to_numpy(float),
            marker="o",
            ms=3,
            label=f"#{row['minimum']}: {row['objective_best']:.3g} ({row['n_points']} pts; {row['methods']})",
        )
    ax.set_xticks(x, names, rotation=60)
    ax.set(ylim=(-0.03, 1.03), ylabel="normalized value (0 = lower, 1 = upper bound)", title="Distinct minima")
    ax.legend(fontsize=6, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    return save_figure(fig, path)


@styled
def alphas_figure(parameters: pd.DataFrame, names: list[str], path: Path) -> Path:
    n = parameters["parameter"].nunique()
    fig, ax = subplots(figsize=(max(6, 0.7 * n + 3), 4.2))
    sns.stripplot(
        data=parameters,
        x="parameter",
        y="value",
        hue="method",
        order=names,
        dodge=True,
        ax=ax,
        size=3.5,
        alpha=0.8,
    )
    ax.axhline(0.0, color="grey", lw=0.8, ls="--")
    ax.set(ylabel="alpha (relative stiffness change)", title="Updated parameters, one point per run")
    ax.tick_params(axis="x", rotation=60 if n > 6 else 0)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    return save_figure(fig, path)
