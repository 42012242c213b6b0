"""Sensitivities and identifiability of an ``analysis`` study, from its tables only.

Asked for with ``report: {sensitivity: {variants: [...]}}`` (``variants``: the variants to
draw, default all). Table:

- ``sensitivity_summary``: variant x point x parameter: the largest |S_f| = |(df/f)/(dp/p)|
  over the modes and the mode it belongs to, the largest |S_MAC|, and the parameter's rank
  (1 = largest |S_f|) at that point; a parameter whose largest |S_f| is far below the
  others' is not identifiable from the frequencies.

Figures: ``sensitivity.png`` (one row per variant and point: frequency and MAC
sensitivities per parameter and mode), ``parameter_correlation.png`` (correlation of the
linearized fit, one heat map per variant and point), ``singular_values.png``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from framework.core.io import save_figure


def _select(df: pd.DataFrame | None, variants: list[str] | None) -> pd.DataFrame | None:
    if df is not None and variants:
        df = df[df["variant"].isin(variants)]
    return None if df is None or df.empty else df


def _panels(df: pd.DataFrame) -> list[tuple[str, str]]:
    return list(dict.fromkeys(zip(df["variant"], df["label"])))


def _title(variant: str, point: str) -> str:
    return point if variant in ("", "default") else f"{variant}, {point}"


def summary(sens: pd.DataFrame) -> pd.DataFrame:
    """Largest relative sensitivities per variant, point and parameter."""
    rows = []
    for (variant, point, parameter), g in sens.groupby(["variant", "label", "parameter"], sort=False):
        f = g["rel_sensitivity_frequency"].abs().to_numpy()
        i = int(np.nanargmax(f)) if np.isfinite(f).any() else 0
        rows.append({"variant": variant, "label": point, "parameter": parameter,
                     "max_abs_frequency_sensitivity": float(np.nanmax(f)) if np.isfinite(f).any() else np.nan,
                     "mode_of_max": g["mode_label"].iloc[i],
                     "max_abs_mac_sensitivity": float(g["rel_sensitivity_mac"].abs().max())})
    out = pd.DataFrame(rows)
    out["rank"] = out.groupby(["variant", "label"])["max_abs_frequency_sensitivity"].rank(
        ascending=False, method="min").astype(int)
    return out


def tables(tables: dict[str, pd.DataFrame], variants: list[str] | None = None) -> dict[str, pd.DataFrame]:
    sens = _select(tables.get("sensitivity"), variants)
    return {} if sens is None else {"sensitivity_summary": summary(sens)}


def figures(tables: dict[str, pd.DataFrame], out_dir: Path, variants: list[str] | None = None, **_) -> list[Path]:
    import matplotlib.pyplot as plt
    import seaborn as sns

    out_dir = Path(out_dir)
    written = []
    sens = _select(tables.get("sensitivity"), variants)
    if sens is not None:
        panels = _panels(sens)
        fig, axes = plt.subplots(len(panels), 2, figsize=(12, 3.4 * len(panels)), squeeze=False)
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
        path = out_dir / "sensitivity.png"
        save_figure(fig, path, dpi=120)
        written.append(path)
    corr = _select(tables.get("parameter_correlation"), variants)
    if corr is not None:
        panels = _panels(corr)
        fig, axes = plt.subplots(1, len(panels), figsize=(5.2 * len(panels), 4.6), squeeze=False)
        for ax, (variant, point) in zip(axes[0], panels):
            sub = corr[(corr["variant"] == variant) & (corr["label"] == point)]
            names = list(dict.fromkeys(sub["parameter"]))
            matrix = sub.pivot(index="parameter", columns="parameter_other", values="correlation").loc[names, names]
            sns.heatmap(matrix, annot=True, fmt=".2f", vmin=-1, vmax=1, cmap="RdBu_r", ax=ax, cbar=False,
                        annot_kws={"fontsize": 7})
            ax.set(xlabel="", ylabel="", title=f"parameter correlation ({_title(variant, point)})")
        fig.tight_layout()
        path = out_dir / "parameter_correlation.png"
        save_figure(fig, path, dpi=120)
        written.append(path)
    ident = _select(tables.get("identifiability"), variants)
    if ident is not None:
        fig, ax = plt.subplots(figsize=(6, 4))
        for (variant, point), g in ident.groupby(["variant", "label"], sort=False):
            ax.semilogy(g["index"], g["singular_value"], "o-",
                        label=f"{_title(variant, point)} (condition {g['condition_number'].iloc[0]:.3g})")
        ax.set(xlabel="index", ylabel="singular value of [S_f; S_MAC]", title="Singular values")
        ax.legend(fontsize=7)
        path = out_dir / "singular_values.png"
        save_figure(fig, path, dpi=120)
        written.append(path)
    return written
