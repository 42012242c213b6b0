"""Figures of updating studies, drawn from the tidy tables only (never from in-memory state).

``updating_figures(tables, out_dir)`` draws every figure the tables support:
convergence.png (best objective vs evaluations: median and 10-90 % band per label),
parameters.png (ratio to initial value per parameter and label, one point per run),
frequencies.png (updated vs measured frequency error and MAC per mode, base case),
validation.png (predicted vs measured frequency error per validation case).
Analyses named in a config's ``report`` section add their own (:mod:`framework.analysis`).
"""

from __future__ import annotations

import logging
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import seaborn as sns  # noqa: E402

from framework.io import save_figure  # noqa: E402

log = logging.getLogger(__name__)


def _group_label(df: pd.DataFrame) -> pd.Series:
    if "variant" in df.columns and df["variant"].nunique() > 1:
        return df["label"] + " [" + df["variant"].astype(str) + "]"
    return df["label"]


def convergence(history: pd.DataFrame, path: Path) -> None:
    """Median and 10-90 % band of the best-so-far objective against evaluations."""
    fig, ax = plt.subplots(figsize=(7, 4.5))
    history = history.assign(group=_group_label(history))
    for group, h in history.groupby("group", sort=True):
        grid = np.unique(np.geomspace(1, max(2, h["evaluation"].max()), 200).astype(int))
        curves = []
        for _, run in h.groupby("run_id"):
            run = run.sort_values("evaluation")
            idx = np.searchsorted(run["evaluation"].to_numpy(), grid, side="right") - 1
            vals = np.where(idx >= 0, run["best_objective"].to_numpy()[np.maximum(idx, 0)], np.nan)
            last = run["evaluation"].max()
            vals = np.where(grid > last, np.nan, vals)
            curves.append(vals)
        c = np.array(curves)
        with np.errstate(all="ignore"):
            med = np.nanmedian(c, axis=0)
            lo, hi = np.nanpercentile(c, 10, axis=0), np.nanpercentile(c, 90, axis=0)
        (line,) = ax.plot(grid, med, label=group)
        ax.fill_between(grid, lo, hi, color=line.get_color(), alpha=0.2)
    ax.set(
        xscale="log",
        yscale="log",
        xlabel="model evaluations",
        ylabel="best objective so far",
        title="Convergence (median, 10-90 % over runs)",
    )
    ax.legend(fontsize=7)
    _save(fig, path)


def parameter_spread(parameters: pd.DataFrame, path: Path) -> None:
    """Updated value per parameter and label: as a ratio to the initial value, or, where an
    initial value is 0 (ratio undefined, e.g. stiffness changes alpha), normalized to the bounds."""
    df = parameters.assign(group=_group_label(parameters))
    use_ratio = df["ratio"].notna().all()
    y, ylabel, ref = ("ratio", "updated / initial value", 1.0) if use_ratio else (
        "normalized", "updated value, normalized to bounds [0, 1]", None)
    n = df["parameter"].nunique()
    fig, ax = plt.subplots(figsize=(max(6, 1.2 * n + 2), 4.5))
    sns.stripplot(data=df, x="parameter", y=y, hue="group", dodge=True, ax=ax, size=4, alpha=0.8)
    if ref is not None:
        ax.axhline(ref, color="grey", lw=0.8, ls="--")
    ax.set(ylabel=ylabel, title="Updated parameters, one point per run")
    ax.legend(fontsize=7)
    _save(fig, path)


def frequencies(modes: pd.DataFrame, path: Path, case: str = "base") -> None:
    df = modes[modes["case"] == case]
    df = df.assign(group=_group_label(df))
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    sns.barplot(data=df, x="mode", y="error_pct", hue="group", ax=axes[0], errorbar=("pi", 100))
    axes[0].axhline(0, color="k", lw=0.8)
    axes[0].set(ylabel="(f_model - f_measured) / f_measured [%]", title=f"Frequency error ({case})")
    sns.barplot(data=df, x="mode", y="mac", hue="group", ax=axes[1], errorbar=("pi", 100))
    axes[1].set(
        ylim=(max(0.0, float(np.nanmin(df["mac"])) - 0.02) if df["mac"].notna().any() else 0, 1.0),
        ylabel="MAC",
        title=f"MAC ({case})",
    )
    for ax in axes:
        ax.legend(fontsize=7)
    _save(fig, path)


def validation(modes: pd.DataFrame, path: Path) -> None:
    df = modes[modes["case"] != "base"]
    if df.empty:
        return
    df = df.assign(group=_group_label(df))
    g = sns.catplot(
        data=df,
        x="mode",
        y="error_pct",
        hue="group",
        col="case",
        kind="bar",
        errorbar=("pi", 100),
        height=3.8,
        aspect=1.1,
    )
    g.set_axis_labels("mode", "predicted - measured [%]")
    g.figure.suptitle("Validation: predictions of the updated models", y=1.03)
    _save(g.figure, path)


def updating_figures(tables: dict[str, pd.DataFrame], out_dir: Path) -> list[Path]:
    """Every figure the tables of an updating study support; returns the files written."""
    root = Path(out_dir)
    written = []
    sns.set_theme(style="whitegrid", context="paper")
    jobs = [
        ("history", convergence, "convergence.png"),
        ("parameters", parameter_spread, "parameters.png"),
        ("modes", frequencies, "frequencies.png"),
        ("modes", validation, "validation.png"),
    ]
    for table, fn, name in jobs:
        df = tables.get(table)
        if df is None or df.empty:
            continue
        try:
            fn(df, root / name)
            if (root / name).exists():
                written.append(root / name)
        except Exception as exc:  # a figure must not lose the tables
            log.warning("figure %s failed: %s", name, exc)
    return written


def _save(fig, path: Path) -> None:
    save_figure(fig, path, dpi=130)
