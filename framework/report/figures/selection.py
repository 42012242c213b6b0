"""Figure of the ``selection`` analysis (:mod:`framework.report.analyses.selection`), drawn
from its ``convergence_summary`` table.

- ``selection.png``: per setting (label and variant), the mean evaluations to reach
  f* + tolerance (grey: not converged) and the mean best value above f*.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from framework.report.figures.style import save_figure, styled, subplots


@styled
def selection_figure(summary: pd.DataFrame, path: Path, title: str = "") -> Path:
    df = summary.assign(setting=summary["label"] + " " + summary["variant"].astype(str))
    fig, axes = subplots(1, 2, figsize=(12, max(3.5, 0.35 * len(df) + 1.5)), sharey=True)
    y = np.arange(len(df))
    colors = np.where(df["converged"], "tab:blue", "tab:gray")
    axes[0].barh(y, df["mean_evaluations_to_converge"].fillna(0), color=colors)
    for i, (conv, val) in enumerate(zip(df["converged"], df["mean_evaluations_to_converge"])):
        axes[0].text(0 if np.isnan(val) else val, i, "  not converged" if not conv else f"  {val:.0f}",
                     va="center", fontsize=7)
    axes[0].set(yticks=y, yticklabels=df["setting"], xlabel="mean evaluations to converge",
                title="Evaluations to reach f* + tol (grey: not converged)")
    axes[1].barh(y, df["mean_best"] - df["f_star"], color=colors)
    axes[1].axvline(df["tolerance"].iloc[0], color="k", ls="--", lw=0.8)
    axes[1].set(xscale="log", xlabel="mean best - f*", title="Mean best value above f*")
    fig.suptitle(title)
    fig.tight_layout()
    return save_figure(fig, path)
