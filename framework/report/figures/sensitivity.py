"""Figures of the ``sensitivity`` analysis (:mod:`framework.report.analyses.sensitivity`),
drawn from the ``sensitivity``, ``parameter_correlation`` and ``identifiability`` tables of
an ``analysis`` study (the variants asked for).

- ``sensitivity.png``: one row per variant and point: frequency and MAC sensitivities per
  parameter and mode;
- ``parameter_correlation.png``: correlation of the linearized fit, one heat map per
  variant and point;
- ``singular_values.png``: singular values of [S_f; S_MAC] per variant and point.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import seaborn as sns

from framework.report.figures.style import save_figure, styled, subplots


def _panels(df: pd.DataFrame) -> list[tuple[str, str]]:
    return list(dict.fromkeys(zip(df["variant"], df["label"])))


def _title(variant: str, point: str) -> str:
    return point if variant in ("", "default") else f"{variant}, {point}"


@styled
def sensitivity_figure(sens: pd.DataFrame, path: Path) -> Path:
    panels = _panels(sens)
    fig, axes = subplots(len(panels), 2, figsize=(12, 3.4 * len(panels)), squeeze=False)
    for row, (variant, point) in zip(axes, panels):
        sub = sens[(sens["variant"] == variant) & (sens["label"] == point)]
        for ax, (col, ylabel, what) in zip(row, (("rel_sensitivity_frequency", "(df/f) / (dp/p)", "frequency"),
                                                 ("rel_sensitivity_mac", "dMAC / (dp/p)", "MAC"))):
            sns.barplot(data=sub, x="parameter", y=col, hue="mode_label", ax=ax)
            ax.axhline(0.0, color="k", lw=0.5)
            ax.set(xlabel="", ylabel=ylabel, title=f"{what} sensitivity ({_title(variant, point)})")
            ax.legend(fontsize=6, ncol=2)
            ax.tick_params(axis="x", rotation=20)
    fig.tight_layout()
    return save_figure(fig, path)


@styled
def correlation_figure(corr: pd.DataFrame, path: Path) -> Path:
    panels = _panels(corr)
    fig, axes = subplots(1, len(panels), figsize=(5.2 * len(panels), 4.6), squeeze=False)
    for ax, (variant, point) in zip(axes[0], panels):
        sub = corr[(corr["variant"] == variant) & (corr["label"] == point)]
        names = list(dict.fromkeys(sub["parameter"]))
        matrix = sub.pivot(index="parameter", columns="parameter_other", values="correlation").loc[names, names]
        sns.heatmap(matrix, annot=True, fmt=".2f", vmin=-1, vmax=1, cmap="RdBu_r", ax=ax, cbar=False,
                    annot_kws={"fontsize": 7})
        ax.set(xlabel="", ylabel="", title=f"parameter correlation ({_title(variant, point)})")
    fig.tight_layout()
    return save_figure(fig, path)


@styled
def singular_values_figure(ident: pd.DataFrame, path: Path) -> Path:
    fig, ax = subplots(figsize=(6, 4))
    for (variant, point), g in ident.groupby(["variant", "label"], sort=False):
        ax.semilogy(g["index"], g["singular_value"], "o-",
                    label=f"{_title(variant, point)} (condition {g['condition_number'].iloc[0]:.3g})")
    ax.set(xlabel="index", ylabel="singular value of [S_f; S_MAC]", title="Singular values")
    ax.legend(fontsize=7)
    return save_figure(fig, path)
