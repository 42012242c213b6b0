"""Figures of the ``modes`` analysis (:mod:`framework.report.analyses.modes`), drawn from
the ``modes`` table of an ``analysis`` study (base case; the analysis selects the rows).

- ``frequencies.png``: measured frequency, the data's reference frequencies per mode and
  the model's paired frequency for each variant, at one point and pairing;
- ``mode_errors.png``: frequency error per mode, one panel per point, one line per
  variant, unmatched modes marked x at 0.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from framework.report.figures.style import save_figure, styled, subplots
from framework.report.figures.updating import mode_ticks


@styled
def frequencies_figure(df: pd.DataFrame, references: list[str], path: Path, pairing: str, point: str) -> Path:
    """``df``: the base-case rows of the modes table at ``point`` with ``pairing``."""
    first = df[df["variant"] == df["variant"].iloc[0]]
    fig, ax = subplots(figsize=(7.5, 4.2))
    ax.plot(first["mode"], first["f_measured_hz"], "ko", label="measured")
    for ref in references:
        ax.plot(first["mode"], first[ref], "s", mfc="none", label=ref)
    for variant, g in df.groupby("variant", sort=False):
        ax.plot(g["mode"], g["f_model_hz"], "x", ms=8, label=f"model, {variant}")
    ticks = mode_ticks(first)
    ax.set_xticks(list(ticks), list(ticks.values()), fontsize=7)
    ax.set(xlabel="measured mode", ylabel="frequency (Hz)",
           title=f"Model at the {point} point vs measured (pairing: {pairing})")
    ax.legend(fontsize=7)
    return save_figure(fig, path)


@styled
def errors_figure(df: pd.DataFrame, path: Path, pairing: str) -> Path:
    """``df``: the base-case rows of the modes table with ``pairing``, every point."""
    points = list(dict.fromkeys(df["label"]))
    colors = {v: f"C{i}" for i, v in enumerate(dict.fromkeys(df["variant"]))}
    width = max(5.0, 0.95 * df["mode"].nunique() + 1.5)
    fig, axes = subplots(1, len(points), figsize=(width * len(points) + 2, 4.4), sharey=True, squeeze=False)
    for ax, point in zip(axes[0], points):
        for variant, g in df[df["label"] == point].groupby("variant", sort=False):
            matched = g["matched"].astype(bool).to_numpy()
            ax.plot(g["mode"], np.where(matched, g["error_pct"], np.nan), "o-", color=colors[variant], label=variant)
            if (~matched).any():
                ax.plot(g["mode"][~matched], np.zeros((~matched).sum()), "x", color=colors[variant], ms=11, mew=2,
                        label=f"{variant}: unmatched")
        ax.axhline(0.0, color="k", lw=0.5)
        ticks = mode_ticks(df)
        ax.set_xticks(list(ticks), list(ticks.values()), fontsize=7)
        ax.set(title=f"{point} parameters", xlabel="measured mode")
    handles = {}
    for ax in axes[0]:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(lab, h)
    fig.legend(list(handles.values()), list(handles), fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 0.95))
    axes[0][0].set_ylabel(f"(f_model - f_measured) / f_measured [%], pairing: {pairing}")
    fig.tight_layout()
    return save_figure(fig, path)
