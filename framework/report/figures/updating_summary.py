"""Figures of the ``updating_summary`` analysis (:mod:`framework.report.analyses.updating_summary`),
drawn from the parameters and modes tables of the runs that did not fail.

- ``updated_ratios.png``: updated / initial value per parameter, one point per run, by algorithm;
- ``updated_errors.png``: frequency error per measured mode (base case), one point per run,
  dashed lines at +-``error_band_pct``.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import seaborn as sns

from framework.report.figures.style import save_figure, styled, subplots
from framework.report.figures.updating import mode_ticks


@styled
def ratios_figure(params: pd.DataFrame, path: Path) -> Path:
    lo, hi = float(params["lower"].min()), float(params["upper"].max())
    fig, ax = subplots(figsize=(9, 4))
    sns.stripplot(data=params, x="parameter", y="ratio", hue="algorithm", dodge=True, ax=ax)
    ax.axhline(1.0, color="k", lw=0.5)
    ax.set(ylabel="updated / initial", title=f"Updated parameters, one point per run (bounds {lo:g}-{hi:g})")
    return save_figure(fig, path)


@styled
def errors_figure(base: pd.DataFrame, path: Path, error_band_pct: float) -> Path:
    fig, ax = subplots(figsize=(9, 4))
    sns.stripplot(data=base, x="mode", y="error_pct", hue="algorithm", dodge=True, ax=ax)
    for sign in (1, -1):
        ax.axhline(sign * error_band_pct, color="r", lw=0.5, ls="--")
    ticks = mode_ticks(base)
    ax.set_xticks(range(len(ticks)), list(ticks.values()), fontsize=7)
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set(xlabel="measured mode", ylabel="(f_model - f_measured) / f_measured [%]",
           title=f"Updated vs measured frequencies, one point per run (dashed: +-{error_band_pct:g} %)")
    return save_figure(fig, path)
