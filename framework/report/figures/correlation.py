"""Correlation figures drawn from the tables ``mac_matrix`` and ``comac`` (and ``geometry``).

- ``mac_matrix.png``: MAC of every measured mode (rows) with every model mode (columns) at
  each state, with frequencies and labels on the axes, and the measured auto-MAC (how
  distinguishable the measured modes are with these sensors); values printed in the cells;
- ``auto_mac_model.png``: auto-MAC of the model's modes at the measured DOFs (off-diagonal
  values near 1 mean the sensors cannot tell those modes apart: spatial aliasing);
- ``comac.png``: COMAC by measured DOF at each state (1: the DOF agrees in every paired
  mode), and on the geometry where the DOFs have positions.
"""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np
import pandas as pd

from framework.report.figures.style import figure, save_figure, styled, subplots

MAX_MODES = 20


def _tick(label: str, f: float) -> str:
    """'1st vertical\n1.64 Hz' for a measured mode, 'model 3 2.80 Hz\n(vertical)' for a model mode."""
    label = str(label)
    if not label.startswith(("mode ", "model ")):
        return f"{textwrap.fill(label, 16)}\n{f:.2f} Hz"
    head, _, kind = label.partition(" (")
    return f"{head} {f:.2f} Hz" + (f"\n({kind}" if kind else "")


def _heatmap(ax, df: pd.DataFrame, title: str, xlabel: str, ylabel: str):
    df = df[(df["i"] <= MAX_MODES) & (df["j"] <= MAX_MODES)]
    rows = df.drop_duplicates("i").sort_values("i")
    cols = df.drop_duplicates("j").sort_values("j")
    grid = df.pivot(index="i", columns="j", values="mac").reindex(index=rows["i"], columns=cols["j"]).to_numpy()
    ax.grid(False)
    im = ax.imshow(grid, vmin=0, vmax=1, cmap="Blues", aspect="auto")
    ax.set_xticks(range(len(cols)), [_tick(lab, f) for lab, f in zip(cols["label_j"], cols["f_j_hz"])],
                  rotation=90, fontsize=6)
    ax.set_yticks(range(len(rows)), [_tick(lab, f) for lab, f in zip(rows["label_i"], rows["f_i_hz"])], fontsize=6)
    if grid.size <= 20 * 20:
        for (r, c), v in np.ndenumerate(grid):
            if np.isfinite(v) and v >= 0.005:
                ax.text(c, r, f"{v:.2f}", ha="center", va="center", fontsize=5 if grid.shape[1] > 10 else 6,
                        color="white" if v > 0.6 else "black")
    ax.set_title(title, fontsize=9)
    ax.set_xlabel(xlabel, fontsize=8)
    ax.set_ylabel(ylabel, fontsize=8)
    return im


@styled
def mac_figure(mac: pd.DataFrame, path: Path) -> Path | None:
    """Measured vs model MAC per state and the measured auto-MAC."""
    panels = [(f"MAC, measured vs model\n({state} parameters)", "model mode", "measured mode", d)
              for state, d in mac[mac["kind"] == "measured_vs_model"].groupby("state", sort=False)]
    auto = mac[mac["kind"] == "auto_measured"]
    if not auto.empty:
        panels.append(("auto-MAC of the measured modes\n(at the sensors)", "measured mode", "measured mode", auto))
    if not panels:
        return None
    width = [max(4.0, 0.45 * d["j"].clip(upper=MAX_MODES).max() + 2.5) for *_, d in panels]
    fig, axes = subplots(1, len(panels), figsize=(sum(width), 4.8), squeeze=False,
                             gridspec_kw={"width_ratios": width, "wspace": 0.45})
    for k, (ax, (title, xl, yl, d)) in enumerate(zip(axes.ravel(), panels)):
        im = _heatmap(ax, d, title, xl, yl)
        if k:  # every panel's rows are the measured modes: label them once, on the left
            ax.set_ylabel("")
            ax.tick_params(labelleft=False)
    fig.colorbar(im, ax=axes.ravel().tolist(), shrink=0.8, label="MAC")
    return save_figure(fig, path)


@styled
def auto_mac_model_figure(mac: pd.DataFrame, path: Path) -> Path | None:
    auto = mac[mac["kind"] == "auto_model"]
    if auto.empty:
        return None
    states = list(dict.fromkeys(auto["state"]))
    n = int(auto["j"].clip(upper=MAX_MODES).max())
    fig, axes = subplots(1, len(states), figsize=(len(states) * (0.42 * n + 3.0), 0.42 * n + 2.5), squeeze=False)
    for ax, state in zip(axes.ravel(), states):
        im = _heatmap(ax, auto[auto["state"] == state], f"auto-MAC of the model modes\nat the sensors ({state})",
                      "model mode", "model mode")
    fig.colorbar(im, ax=axes.ravel().tolist(), shrink=0.8, label="MAC")
    return save_figure(fig, path)


@styled
def comac_figure(comac: pd.DataFrame, geometry: pd.DataFrame | None, path: Path) -> Path | None:
    """COMAC per DOF (a marker per state) and, where DOFs have positions, on the geometry."""
    if comac.empty or comac["comac"].isna().all():
        return None
    states = list(dict.fromkeys(comac["state"]))
    dofs = list(dict.fromkeys(comac["dof"]))
    located = comac.dropna(subset=["x", "y", "z"])
    on_geometry = geometry is not None and not geometry.empty and located["dof"].nunique() > 3
    fig = figure(figsize=(max(6.0, 0.22 * len(dofs) + 3), 4.0 + (5.0 if on_geometry else 0)))
    ax = fig.add_axes([0.1, 0.62, 0.85, 0.33] if on_geometry else [0.1, 0.25, 0.85, 0.65])
    for k, state in enumerate(states):
        d = comac[comac["state"] == state].set_index("dof").reindex(dofs)
        n_pairs = int(d["n_pairs"].max())
        ax.plot(np.arange(len(dofs)), d["comac"], "os^D"[k % 4], ms=5, mfc="none" if k else None,
                label=f"{state} ({n_pairs} paired modes)")
    low = float(np.nanmin(comac["comac"]))
    ax.set_xticks(range(len(dofs)), dofs, rotation=90, fontsize=6 if len(dofs) > 20 else 8)
    ax.set(ylim=(max(0.0, low - 0.15 * (1 - low) - 0.005), 1.0 + 0.05 * (1 - low) + 0.001), ylabel="COMAC",
           title="COMAC by measured DOF (1 = the DOF agrees in every paired mode; axis from the lowest value)")
    ax.legend(fontsize=7, loc="lower left")
    if on_geometry:
        from framework.report.figures.shapes import Geometry, _draw_structure, _frame

        geo = Geometry(geometry)
        state = states[-1]
        d = located[located["state"] == state]
        points = d.groupby(["x", "y", "z"], as_index=False)["comac"].min()
        kw = {"projection": "3d"} if geo.is_3d else {}
        gax = fig.add_axes([0.05, 0.02, 0.8, 0.45], **kw)
        _draw_structure(gax, geo, None, 0.0, set())
        colours = dict(c=points["comac"], cmap="RdYlGn", vmin=max(0.0, low - 0.05), vmax=1.0, s=30)
        if geo.is_3d:
            sc = gax.scatter(points["x"], points["y"], points["z"], depthshade=False, **colours)
        else:
            a, b = geo.axes
            cols = ["x", "y", "z"]
            sc = gax.scatter(points[cols[a]], points[cols[b]], zorder=5, **colours)
        fig.colorbar(sc, ax=gax, shrink=0.7, label=f"COMAC ({state}; lowest DOF at each sensor)")
        gax.set_title(f"COMAC at the sensors ({state} parameters)", fontsize=9)
        _frame(gax, geo)
    return save_figure(fig, path)
