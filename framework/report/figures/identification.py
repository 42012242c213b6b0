"""Figures of the identification study, drawn from its tables only.

- ``stability_<label>.png``: stability diagram (poles over model orders, stable ones filled,
  the selected modes as dashed lines) of the first record of each subspace run, with the
  mode indicator sum_k |H1_k| of the same test's peak-picking run behind it when there is one;
- ``frf_<label>.png``: |H1|, phase and coherence of the stored channels of each
  peak-picking run, candidate peaks as dashed lines (accepted black, rejected grey).

With several runs of one test (``runs`` > 1) the run with the lowest seed is drawn; with
variants the variant is added to the file name.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd

from framework.identification.rows import INDICATOR
from framework.report.figures.style import save_figure, styled, subplots

SUBSPACE = ("n4sid", "ssi_cov")


def _of_run(table: pd.DataFrame | None, run_id: str, record: str | None = None) -> pd.DataFrame:
    if table is None or table.empty or "run_id" not in table:
        return pd.DataFrame()
    sel = table[table["run_id"] == run_id]
    return sel if record is None else sel[sel["record"] == record]


def _stem(kind: str, label: str, variant: str) -> str:
    name = f"{kind}_{label}" if variant in ("", "default") else f"{kind}_{label}_{variant}"
    return re.sub(r"[^A-Za-z0-9_.=+-]", "_", name)


def _first_runs(runs: pd.DataFrame, methods: tuple[str, ...]) -> pd.DataFrame:
    """The run with the lowest seed of every (label, variant, method) among ``methods``."""
    sel = runs[runs["method"].isin(methods)] if "method" in runs else runs.iloc[0:0]
    if "status" in sel:
        sel = sel[sel["status"] != "error"]
    return sel.sort_values("seed", kind="stable").drop_duplicates(["label", "variant", "method"])


@styled
def plot_stability(
    stability: pd.DataFrame,
    path: str | Path,
    selected_hz: np.ndarray | None = None,
    indicator: tuple[np.ndarray, np.ndarray] | None = None,
    title: str = "",
    f_max_hz: float | None = None,
) -> Path:
    """Stability diagram: poles (order vs frequency), stable ones filled; optional selected
    frequencies (dashed) and a mode indicator (frequency, values) on a log axis behind."""
    fmax = f_max_hz or float(stability["frequency_hz"].max())
    tab = stability[stability["frequency_hz"] <= fmax]
    fig, ax = subplots(figsize=(8, 5))
    phys = tab[tab["physical"].astype(bool) & ~tab["stable"].astype(bool)]
    ax.plot(phys["frequency_hz"], phys["order"], "o", ms=3, mfc="none", mec="0.6", label="new / unstable")
    st = tab[tab["stable"].astype(bool)]
    ax.plot(st["frequency_hz"], st["order"], "o", ms=3.5, color="C3", label="stable (f, MAC)")
    for f in [] if selected_hz is None else selected_hz:
        ax.axvline(f, color="C0", lw=0.7, ls="--")
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("model order")
    ax.set_xlim(0, fmax)
    if indicator is not None:
        ax2 = ax.twinx()
        fi, vi = indicator
        sel = fi <= fmax
        ax2.semilogy(fi[sel], vi[sel], color="0.3", lw=0.7)
        ax2.set_ylabel("mode indicator (sum |H1|)")
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title(title or "stability diagram")
    fig.tight_layout()
    return save_figure(fig, path)


#: channels drawn in an FRF figure (the mode indicator shows every channel)
MAX_FRF_CHANNELS = 4


@styled
def plot_frf(frf: pd.DataFrame, path: str | Path, peaks: pd.DataFrame | None = None, title: str = "",
             input_label: str = "input") -> Path:
    """|H1| (log), phase and coherence of every channel of an ``frf`` table (one record)."""
    fig, axes = subplots(3, 1, figsize=(8, 8), sharex=True, gridspec_kw={"height_ratios": [2, 1, 1]})
    stored = [c for c in dict.fromkeys(frf["channel"]) if c != INDICATOR]
    channels = stored[:MAX_FRF_CHANNELS]  # more overlaid curves are unreadable: the indicator sums them all
    indicator = frf[frf["channel"] == INDICATOR]
    if not indicator.empty:  # mode indicator: sum over every output channel of |H1|
        axes[0].semilogy(indicator["frequency_hz"], indicator["magnitude"], color="0.4", lw=1.6, alpha=0.6,
                         label="mode indicator: sum of |H1| over all outputs")
    for channel in channels:
        rows = frf[frf["channel"] == channel]
        axes[0].semilogy(rows["frequency_hz"], rows["magnitude"], lw=0.8, label=channel)
        axes[1].plot(rows["frequency_hz"], rows["phase_deg"], lw=0.6)
        axes[2].plot(rows["frequency_hz"], rows["coherence"], lw=0.6)
    if peaks is not None:
        for f, accepted in zip(peaks["frequency_hz"], peaks["accepted"]):
            for ax in axes:
                ax.axvline(f, color="k" if accepted else "0.7", ls="--", lw=0.6)
        axes[0].plot([], [], color="k", ls="--", lw=0.6, label="picked peak (grey: rejected)")
    axes[0].set_ylabel(f"|H1| (output / {input_label})")
    axes[1].set_ylabel("phase (deg)")
    axes[2].set_ylabel("coherence")
    axes[2].set_ylim(0, 1.05)
    axes[2].set_xlabel("frequency (Hz)")
    axes[0].legend(fontsize=7, ncol=2)
    shown = (f"{len(channels)} of {len(stored)} stored channels" if len(stored) > len(channels)
             else f"{len(channels)} stored channel" + ("s" if len(channels) > 1 else ""))
    axes[0].set_title((title or "H1 FRF") + f"\n({shown} and the mode indicator)", fontsize=10)
    fig.tight_layout()
    return save_figure(fig, path)


def _indicator(tables: dict, run: pd.Series) -> tuple[np.ndarray, np.ndarray] | None:
    """The indicator of the peak-picking run of the same test (same variant if there is one)."""
    runs = tables["runs"]
    pp = _first_runs(runs[runs["label"] == run["label"]], ("peak_picking",))
    if pp.empty:
        return None
    same = pp[pp["variant"] == run["variant"]]
    pp_run = (same if not same.empty else pp).iloc[0]
    rows = _of_run(tables.get("frf"), pp_run["run_id"])
    rows = rows[rows["channel"] == INDICATOR]
    if rows.empty:
        return None
    return rows["frequency_hz"].to_numpy(float), rows["magnitude"].to_numpy(float)


def stability_figures(tables: dict, out_dir: Path) -> list[Path]:
    runs = tables.get("runs")
    if runs is None or runs.empty:
        return []
    written = []
    for _, run in _first_runs(runs, SUBSPACE).iterrows():
        stab = _of_run(tables.get("stability"), run["run_id"])
        if stab.empty:
            continue
        record = stab["record"].iloc[0]
        stab = stab[stab["record"] == record]
        ident = _of_run(tables.get("identified"), run["run_id"], record)
        title = (f"{run['structure']}, {record}, {run['method']} (orders {run['orders_min']}-{run['orders_max']}, "
                 f"{100 * run['freq_tol']:g} %, MAC {run['mac_min']:g})")
        written.append(plot_stability(stab, out_dir / f"{_stem('stability', run['label'], run['variant'])}.png",
                                      ident["frequency_hz"].to_numpy(float) if not ident.empty else None,
                                      _indicator(tables, run), title, float(run["band_max_hz"])))
    return written


def frf_figures(tables: dict, out_dir: Path) -> list[Path]:
    runs = tables.get("runs")
    if runs is None or runs.empty:
        return []
    written = []
    for _, run in _first_runs(runs, ("peak_picking",)).iterrows():
        frf = _of_run(tables.get("frf"), run["run_id"])
        if frf.empty:
            continue
        record = frf["record"].iloc[0]
        n = int(run["records"])
        what = f"H1 averaged over {n} records" if n > 1 else f"H1 of {record}"
        title = f"{run['structure']}, {run['test']} ({run['label']}): {what}"
        written.append(plot_frf(frf, out_dir / f"{_stem('frf', run['label'], run['variant'])}.png",
                                _of_run(tables.get("peaks"), run["run_id"]), title, str(run["input_channel"])))
    return written
