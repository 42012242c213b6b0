"""Mode-shape figures drawn from the tables ``geometry``, ``mode_shapes`` and ``sensor_shapes``.

- ``shapes_model.png``: the undeformed geometry (grey) and the model's modes (deformed, each
  element coloured by its group: deck, pylon, cable, ...), at the updated point when there is
  one, else the initial one;
- ``shapes_paired_<state>.png``: for each measured mode, the paired model mode at that state
  with the measured shape at the sensors overlaid (black markers and dashed lines, scaled
  onto the model mode by the modal scale factor); MAC and frequencies in each title.

A 3-D structure is drawn in 3-D, a planar one in its plane; without geometry the shapes are
drawn channel by channel (shape value against measured DOF). The displacement scale is
chosen per figure (largest translation = 12 % of the structure's size) and said in the title.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path

import numpy as np
import pandas as pd

from framework.report.figures.style import figure, save_figure, styled, subplots

log = logging.getLogger(__name__)

#: largest drawn translation as a fraction of the structure's largest dimension (a line of
#: nodes, a beam or a shear building, gets more)
DEFORMATION_FRACTION = 0.12
LINE_DEFORMATION_FRACTION = 0.25
GROUP_COLOURS = {"deck": "tab:blue", "pylon": "tab:red", "cable": "tab:green", "column": "tab:orange",
                 "slab": "tab:blue", "storey": "tab:blue", "bracket": "tab:purple", "structure": "tab:blue",
                 "connection": "tab:gray", "": "tab:blue"}
MAX_PANELS = 12


class Geometry:
    """Nodes and elements of a ``geometry`` table, with the plane or space to draw them in."""

    def __init__(self, geometry: pd.DataFrame):
        nodes = geometry[geometry["kind"] == "node"]
        self.tags = nodes["tag"].astype(int).to_numpy()
        self.xyz = nodes[["x", "y", "z"]].to_numpy(float)
        self.index = {t: i for i, t in enumerate(self.tags)}
        self.unit = str(nodes["unit"].iloc[0]) if "unit" in nodes and len(nodes) else "m"
        els = geometry[geometry["kind"] == "element"]
        self.elements = [([self.index[int(n)] for n in str(ns).split() if int(n) in self.index], str(g))
                         for ns, g in zip(els["nodes"], els["group"].fillna(""))]
        span = np.ptp(self.xyz, axis=0) if len(self.xyz) else np.zeros(3)
        self.axes = [k for k in range(3) if span[k] > 1e-9 * max(span.max(), 1e-30)]
        self.is_3d = len(self.axes) == 3
        #: drawn size of the largest translation, as a fraction of the structure's size
        self.fraction = DEFORMATION_FRACTION if len(self.axes) > 1 else LINE_DEFORMATION_FRACTION
        if len(self.axes) < 2:  # a line: draw in the plane of that axis and the next one
            first = self.axes[0] if self.axes else 2
            self.axes = sorted({first, (first + 1) % 3})
        self.size = float(span.max()) if span.max() > 0 else 1.0

    def segments(self, xyz: np.ndarray):
        """(points (k, 3), group) of each element: its nodes in order, closed for more than two."""
        for nodes, group in self.elements:
            if len(nodes) < 2:
                continue
            order = nodes + [nodes[0]] if len(nodes) > 2 else nodes
            yield xyz[order], group


def _axes(fig, n: int, is_3d: bool):
    cols = min(n, 4 if not is_3d else 3)
    rows = math.ceil(n / cols)
    fig.set_size_inches(4.4 * cols, 4.0 * rows)
    kw = {"projection": "3d"} if is_3d else {}
    axes = [fig.add_subplot(rows, cols, i + 1, **kw) for i in range(n)]
    fig.subplots_adjust(hspace=0.55 if not is_3d else 0.3, wspace=0.3)
    return axes


def _plot_line(ax, pts: np.ndarray, geo: Geometry, **kw):
    if geo.is_3d:
        ax.plot(pts[:, 0], pts[:, 1], pts[:, 2], **kw)
    else:
        a, b = geo.axes
        ax.plot(pts[:, a], pts[:, b], **kw)


def _draw_structure(ax, geo: Geometry, disp: np.ndarray | None, scale: float, groups_seen: set):
    for pts, _ in geo.segments(geo.xyz):
        _plot_line(ax, pts, geo, color="0.75", lw=0.6)
    if disp is None:
        return
    moved = geo.xyz + scale * np.nan_to_num(disp)
    for pts, group in geo.segments(moved):
        label = group if group not in groups_seen else None
        groups_seen.add(group)
        _plot_line(ax, pts, geo, color=GROUP_COLOURS.get(group, "tab:blue"), lw=1.2 if group != "cable" else 0.8,
                   label=label)


def _frame(ax, geo: Geometry):
    names = "xyz"
    if geo.is_3d:
        # every axis at least a quarter of the largest, so that a deflection across a slender
        # structure (a bridge deck swaying sideways) is seen
        lo, hi = geo.xyz.min(axis=0), geo.xyz.max(axis=0)
        span = np.maximum(hi - lo, 0.25 * (hi - lo).max())
        mid = (lo + hi) / 2
        ax.set_xlim(mid[0] - span[0] / 2, mid[0] + span[0] / 2)
        ax.set_ylim(mid[1] - span[1] / 2, mid[1] + span[1] / 2)
        ax.set_zlim(mid[2] - span[2] / 2, mid[2] + span[2] / 2)
        ax.set_box_aspect(span)
        ax.view_init(elev=30, azim=-48)
        ax.set_xlabel(f"x [{geo.unit}]", fontsize=7)
        ax.set_ylabel(f"y [{geo.unit}]", fontsize=7)
        ax.set_zlabel(f"z [{geo.unit}]", fontsize=7)
        ax.tick_params(labelsize=6)
    else:
        a, b = geo.axes
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel(f"{names[a]} [{geo.unit}]", fontsize=8)
        ax.set_ylabel(f"{names[b]} [{geo.unit}]", fontsize=8)
        ax.tick_params(labelsize=7)


def _node_disp(modes: pd.DataFrame, geo: Geometry) -> np.ndarray:
    u = np.full((len(geo.tags), 3), np.nan)
    idx = [geo.index[int(t)] for t in modes["node"]]
    u[idx] = modes[["ux", "uy", "uz"]].to_numpy(float)
    return u


@styled
def model_modes_figure(geometry: pd.DataFrame, mode_shapes: pd.DataFrame, path: Path, state: str) -> Path | None:
    """The model's modes at ``state`` on the undeformed geometry."""
    geo = Geometry(geometry)
    df = mode_shapes[mode_shapes["state"] == state]
    modes = sorted(df["mode"].unique())[:MAX_PANELS]
    if not modes:
        return None
    fig = figure()
    axes = _axes(fig, len(modes), geo.is_3d)
    scale = geo.fraction * geo.size
    seen: set = set()
    for ax, m in zip(axes, modes):
        d = df[df["mode"] == m]
        _draw_structure(ax, geo, _node_disp(d, geo), scale, seen)
        mtype = d["mode_type"].iloc[0] if "mode_type" in d and isinstance(d["mode_type"].iloc[0], str) else ""
        ax.set_title(f"mode {m}: {d['f_hz'].iloc[0]:.3f} Hz" + (f" ({mtype})" if mtype else ""), fontsize=9)
        _frame(ax, geo)
    handles, labels = axes[0].get_legend_handles_labels()
    if len(set(labels)) > 1:
        fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=8, frameon=False)
    fig.suptitle(f"Model mode shapes ({state} parameters); grey: undeformed; largest translation drawn as "
                 f"{geo.fraction:.0%} of the structure's size", fontsize=10, y=1.02)
    return save_figure(fig, path)


@styled
def paired_figure(geometry: pd.DataFrame | None, mode_shapes: pd.DataFrame, sensors: pd.DataFrame, path: Path,
                  state: str) -> Path | None:
    """Each measured mode over its paired model mode at ``state``."""
    s = sensors[sensors["state"] == state]
    if s.empty:
        return None
    measured = sorted(s["measured_mode"].unique())[:MAX_PANELS]
    channels = (s["layout"] == "channels").all() or geometry is None or geometry.empty
    if channels:
        return _paired_channels(s, measured, path, state)
    geo = Geometry(geometry)
    df = mode_shapes[mode_shapes["state"] == state]
    fig = figure()
    axes = _axes(fig, len(measured), geo.is_3d)
    scale = geo.fraction * geo.size
    seen: set = set()
    for ax, i in zip(axes, measured):
        si = s[s["measured_mode"] == i]
        head = si.iloc[0]
        _draw_structure(ax, geo, _node_disp(df[df["mode"] == head["model_mode"]], geo), scale, seen)
        p0 = si[["x", "y", "z"]].to_numpy(float)
        pm = p0 + scale * si[["measured_ux", "measured_uy", "measured_uz"]].to_numpy(float)
        for a, b in zip(p0, pm):
            _plot_line(ax, np.array([a, b]), geo, color="k", lw=0.6, ls=":")
        label = "measured (scaled by MSF)" if "measured" not in seen else None
        seen.add("measured")
        if geo.is_3d:
            ax.scatter(pm[:, 0], pm[:, 1], pm[:, 2], color="k", s=10, marker="o", label=label, depthshade=False)
        else:
            a_, b_ = geo.axes
            ax.scatter(pm[:, a_], pm[:, b_], color="k", s=14, marker="o", label=label, zorder=5)
        flag = "" if head["matched"] else " UNMATCHED"
        ax.set_title(f"{head['measured_label']} {head['f_measured_hz']:.3f} Hz | model {head['model_mode']} "
                     f"{head['f_model_hz']:.3f} Hz\nMAC {head['mac']:.3f}{flag}", fontsize=8)
        _frame(ax, geo)
    handles, labels = [], []
    for ax in axes:
        h, lab = ax.get_legend_handles_labels()
        handles += h
        labels += lab
    if handles:
        fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=8, frameon=False)
    fig.suptitle(f"Measured shapes at the sensors over the paired model modes ({state} parameters); "
                 f"largest model translation drawn as {geo.fraction:.0%} of the structure's size",
                 fontsize=10, y=1.02)
    return save_figure(fig, path)


@styled
def _paired_channels(s: pd.DataFrame, measured: list, path: Path, state: str) -> Path:
    """Without geometry: shape value per measured DOF, model line and measured markers."""
    n = len(measured)
    cols = min(n, 2)
    rows = math.ceil(n / cols)
    fig, axes = subplots(rows, cols, figsize=(6.5 * cols, 2.6 * rows), squeeze=False)
    for ax, i in zip(axes.ravel(), measured):
        si = s[s["measured_mode"] == i].sort_values("x")
        head = si.iloc[0]
        ax.plot(si["x"], si["model_ux"], "x-", color="tab:blue", lw=0.4, ms=4, label="model (line: channel order)")
        ax.plot(si["x"], si["measured_ux"], "o", color="k", ms=3, label="measured (scaled by MSF)")
        ax.axhline(0, color="0.7", lw=0.6)
        flag = "" if head["matched"] else " UNMATCHED"
        ax.set_title(f"{head['measured_label']} {head['f_measured_hz']:.3f} Hz | model {head['model_mode']} "
                     f"{head['f_model_hz']:.3f} Hz, MAC {head['mac']:.3f}{flag}", fontsize=8)
        ax.set(xlabel="measured DOF (channel number, as in the data)", ylabel="shape (largest = 1)")
    for ax in axes.ravel()[n:]:
        ax.axis("off")
    axes.ravel()[0].legend(fontsize=7)
    fig.suptitle(f"Measured and paired model shapes by channel ({state} parameters; the data hold no "
                 "coordinates)", fontsize=10)
    fig.tight_layout()
    return save_figure(fig, path)
