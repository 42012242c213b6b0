"""Figures of updating studies, drawn from the tidy tables only (never from in-memory state).

``updating_figures(tables, out_dir)`` draws every figure the tables support:
convergence.png (best objective vs evaluations: median and 10-90 % band per label),
parameters.png (ratio to initial value per parameter and label, one point per run),
frequencies.png (frequency error and MAC per measured mode, every run a point, medians marked,
measured frequency and mode label on the axis), validation.png (predicted vs measured
frequency error per validation case, likewise). A few outlying runs never set an axis: when
the full range exceeds four times the 5-95 % range, the axis shows the latter and the figure
says how many values lie off the scale.
Analyses named in a config's ``report`` section add their own (:mod:`framework.report.analyses`).
"""

from __future__ import annotations

import logging
import textwrap
from pathlib import Path

import numpy as np
import pandas as pd
import seaborn as sns

from framework.report.figures.style import save_figure, styled, subplots

log = logging.getLogger(__name__)


def _group_label(df: pd.DataFrame) -> pd.Series:
    if "variant" in df.columns and df["variant"].nunique() > 1:
        return df["label"] + " [" + df["variant"].astype(str) + "]"
    return df["label"]


@styled
def convergence(history: pd.DataFrame, path: Path) -> None:
    """Median and 10-90 % band of the best-so-far objective against evaluations."""
    fig, ax = subplots(figsize=(7, 4.5))
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
    save_figure(fig, path)


@styled
def parameter_spread(parameters: pd.DataFrame, path: Path) -> None:
    """Updated value per parameter and label: as a ratio to the initial value, or, where an
    initial value is 0 (ratio undefined, e.g. stiffness changes alpha), normalized to the bounds."""
    df = parameters.assign(group=_group_label(parameters))
    use_ratio = df["ratio"].notna().all() and np.isfinite(df["ratio"]).all()
    units = df["unit"].dropna().unique() if "unit" in df else []
    if use_ratio:
        y, ylabel, ref = "ratio", "updated / initial value (ratio)", 1.0
    elif len(units) == 1:  # e.g. relative stiffness changes alpha, initial 0: the value itself
        y, ylabel, ref = "value", f"updated value [{units[0]}]", 0.0
    else:
        y, ylabel, ref = "normalized", "updated value, normalized to bounds (0 = lower, 1 = upper)", None
    n = df["parameter"].nunique()
    fig, ax = subplots(figsize=(max(6, 1.2 * n + 2), 4.5))
    sns.stripplot(data=df, x="parameter", y=y, hue="group", dodge=True, ax=ax, size=4, alpha=0.8)
    if ref is not None:
        ax.axhline(ref, color="grey", lw=0.8, ls="--")
    lim = robust_limits(df[y])
    note = ""
    if lim is not None:
        ax.set_ylim(lim[0], lim[1])
        note = f"; {lim[2]} value(s) off the scale"
    if use_ratio:
        names = list(dict.fromkeys(df["parameter"]))
        first = df.drop_duplicates("parameter").set_index("parameter")
        ax.set_xticks(range(len(names)), [f"{p}\ninitial {first.loc[p, 'initial']:.4g} {first.loc[p, 'unit']}"
                                          for p in names], fontsize=7)
    ax.set(ylabel=ylabel, title=f"Updated parameters, one point per run{note}")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    save_figure(fig, path)


def mode_ticks(df: pd.DataFrame) -> dict[int, str]:
    """Tick label of each measured mode: number, label (mode type) and measured frequency."""
    out = {}
    for mode, g in df.groupby("mode", sort=True):
        label = g["mode_label"].dropna().iloc[0] if "mode_label" in g and g["mode_label"].notna().any() else ""
        f = g["f_measured_hz"].dropna().iloc[0] if "f_measured_hz" in g and g["f_measured_hz"].notna().any() else None
        label = textwrap.fill(str(label), 14) if label != "" else ""
        out[int(mode)] = "\n".join(filter(None, [str(int(mode)), label,
                                                 f"{f:.2f} Hz" if f is not None else ""]))
    return out


def robust_limits(values, pad: float = 0.15, factor: float = 4.0) -> tuple[float, float, int] | None:
    """Axis limits that a few outliers do not set: the 5-95 % range of the values, widened by
    ``pad``, when the full range is more than ``factor`` times it; else None. Also returns the
    number of values outside (to be said on the figure)."""
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    if v.size < 5:
        return None
    lo, hi = np.percentile(v, [5, 95])
    full = v.max() - v.min()
    inner = max(hi - lo, 1e-12 * max(1.0, abs(hi)))
    if full <= factor * inner:
        return None
    lo, hi = lo - pad * inner, hi + pad * inner
    return float(lo), float(hi), int(((v < lo) | (v > hi)).sum())


def _points_by_mode(ax, df: pd.DataFrame, y: str, ticks: dict[int, str]) -> None:
    """One marker per run at each mode (groups side by side) and a bar at each group's median."""
    groups = list(dict.fromkeys(df["group"]))
    modes = sorted(ticks)
    width = 0.8 / max(len(groups), 1)
    for k, group in enumerate(groups):
        g = df[df["group"] == group]
        colour = f"C{k % 10}"
        off = (k - (len(groups) - 1) / 2) * width
        for m in modes:
            vals = g.loc[g["mode"] == m, y].to_numpy(float)
            vals = vals[np.isfinite(vals)]
            if vals.size == 0:
                continue
            x = modes.index(m) + off
            ax.plot(np.full(vals.size, x), vals, "o", ms=3, alpha=0.7, color=colour,
                    label=group if m == modes[0] else None)
            ax.plot([x - width / 2.5, x + width / 2.5], [np.nanmedian(vals)] * 2, color=colour, lw=1.5)
    ax.set_xticks(range(len(modes)), [ticks[m] for m in modes], fontsize=7)
    ax.set_xlabel("measured mode")
    lim = robust_limits(df[y])
    if lim is not None:
        ax.set_ylim(lim[0], lim[1])
        ax.text(0.99, 0.01, f"{lim[2]} run(s) off the scale", transform=ax.transAxes, ha="right", va="bottom",
                fontsize=7, color="0.3")


@styled
def frequencies(modes: pd.DataFrame, path: Path, case: str = "base") -> None:
    """Frequency error and MAC of the updated model per measured mode: every run a point."""
    df = modes[(modes["case"] == case) & (modes["mode"] > 0)]
    df = df.assign(group=_group_label(df))
    ticks = mode_ticks(df)
    fig, axes = subplots(2, 1, figsize=(max(8, 1.1 * len(ticks) + 3), 8.5))
    _points_by_mode(axes[0], df, "error_pct", ticks)
    axes[0].axhline(0, color="k", lw=0.8)
    axes[0].set(ylabel="(f_model - f_measured) / f_measured [%]",
                title=f"Frequency error of the updated models ({case})")
    _points_by_mode(axes[1], df, "mac", ticks)
    axes[1].set(ylabel="MAC (updated model vs measured)", title=f"MAC ({case})")
    if axes[1].get_ylim()[1] > 1.0:
        axes[1].set_ylim(top=1.0005)
    axes[0].legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    fig.subplots_adjust(hspace=0.5)
    fig.suptitle("One point per run; bar: median over the runs of each algorithm", fontsize=9, y=0.95)
    save_figure(fig, path)


@styled
def validation(modes: pd.DataFrame, path: Path) -> None:
    """Predicted - measured frequency per validation case and mode: every run a point."""
    df = modes[(modes["case"] != "base") & (modes["mode"] > 0)]
    if df.empty:
        return
    df = df.assign(group=_group_label(df))
    cases = list(dict.fromkeys(df["case"]))
    fig, axes = subplots(1, len(cases), figsize=(5.5 * len(cases), 4.4), squeeze=False, sharey=True)
    for ax, case in zip(axes[0], cases):
        d = df[df["case"] == case]
        _points_by_mode(ax, d, "error_pct", mode_ticks(d))
        ax.axhline(0, color="k", lw=0.8)
        ax.set(title=f"validation case {case}", ylabel="(f_predicted - f_measured) / f_measured [%]")
    axes[0][0].legend(fontsize=7)
    fig.suptitle("Predictions of the updated models: one point per run; bar: median", fontsize=9, y=1.0)
    save_figure(fig, path)


def updating_figures(tables: dict[str, pd.DataFrame], out_dir: Path) -> list[Path]:
    """Every figure the tables of an updating study support; returns the files written."""
    root = Path(out_dir)
    written = []
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
