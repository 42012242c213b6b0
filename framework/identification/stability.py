"""Stability diagram over model orders and automatic selection of stable physical modes.

A pole at order n_j is *stable* when the pole of the previous order n_(j-1) nearest in
frequency differs by less than ``freq_tol`` (relative, 1 %) and its shape has
MAC > ``mac_min`` (0.9 lab frame, 0.8 bridge) with it, and the pole is physical:
0 < zeta < ``damping_max``. Stable poles are clustered by frequency (a new cluster starts
where consecutive sorted frequencies differ by more than ``freq_tol``); a cluster that is
stable at no fewer than ``min_fraction`` of the orders and whose frequencies scatter by
less than ``max_spread`` (1.4826 x median absolute deviation / median, robust to a
noise pole joining a physical cluster) and whose median modal phase collinearity (MPC)
is at least ``mpc_min`` is a mode. Noise poles can pass the order-to-order test but wander
over the orders and have complex shapes (MPC ~ 0); normal modes of a classically damped
structure stay put and have MPC ~ 1. A mode's frequency and damping are the medians over
its cluster, its shape the real shape of the pole nearest the median frequency.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from framework.core.correlation import mac_matrix
from framework.core.errors import InputError
from framework.identification.subspace import Poles, modal_phase_collinearity, real_shape


def stability_table(
    poles: Poles,
    freq_tol: float = 0.01,
    mac_min: float = 0.9,
    damping_max: float = 0.2,
    band_hz: tuple[float, float] | None = None,
) -> pd.DataFrame:
    """``poles.table`` plus columns mpc, df_rel, mac_prev, physical, stable (one row per pole)."""
    if not 0 < freq_tol < 1 or not 0 <= mac_min <= 1:
        raise InputError(f"stability: freq_tol in (0, 1) and mac_min in [0, 1] required, got {freq_tol!r}, {mac_min!r}")
    tab = poles.table.copy()
    f = tab["frequency_hz"].to_numpy()
    z = tab["damping_ratio"].to_numpy()
    physical = (z > 0) & (z < damping_max)
    if band_hz is not None:
        physical &= (f >= band_hz[0]) & (f <= band_hz[1])
    df_rel = np.full(len(tab), np.nan)
    mac_prev = np.full(len(tab), np.nan)
    orders = poles.orders
    order_col = tab["order"].to_numpy()
    for prev, cur in zip(orders[:-1], orders[1:]):
        ip = np.flatnonzero(order_col == prev)
        ic = np.flatnonzero(order_col == cur)
        if ip.size == 0 or ic.size == 0:
            continue
        near = ip[np.argmin(np.abs(f[ic][:, None] - f[ip][None, :]), axis=1)]
        df_rel[ic] = np.abs(f[ic] - f[near]) / f[near]
        m = mac_matrix(poles.shapes[near].T, poles.shapes[ic].T)  # rows: current, cols: previous
        mac_prev[ic] = np.diag(m)
    tab["mpc"] = [modal_phase_collinearity(v) for v in poles.shapes]
    tab["df_rel"] = df_rel
    tab["mac_prev"] = mac_prev
    tab["physical"] = physical
    tab["stable"] = physical & (df_rel < freq_tol) & (mac_prev > mac_min)
    return tab


@dataclass(frozen=True)
class SelectedModes:
    """Automatically selected modes: ``table`` (one row per mode) and real ``shapes`` (n_out, m)."""

    table: pd.DataFrame
    shapes: np.ndarray
    output_labels: tuple[str, ...]


def select_modes(
    poles: Poles,
    stability: pd.DataFrame,
    freq_tol: float = 0.01,
    min_fraction: float = 0.5,
    max_spread: float = 0.0025,
    mpc_min: float = 0.5,
) -> SelectedModes:
    """Cluster stable poles by frequency; keep clusters stable at >= min_fraction of the
    orders with a relative frequency scatter < max_spread."""
    n_orders = len(poles.orders)
    min_count = max(2, math.ceil(min_fraction * (n_orders - 1)))
    st = stability[stability["stable"]].sort_values("frequency_hz")
    rows, shapes = [], []
    if len(st):
        f = st["frequency_hz"].to_numpy()
        breaks = np.flatnonzero(np.diff(f) / f[:-1] > freq_tol) + 1
        for group in np.split(np.arange(len(st)), breaks):
            sub = st.iloc[group]
            n_stable = sub["order"].nunique()
            if n_stable < min_count:
                continue
            fm = float(np.median(sub["frequency_hz"]))
            mad = 1.4826 * np.median(np.abs(sub["frequency_hz"].to_numpy() - fm))
            if mad > max_spread * fm:
                continue
            mpc = float(np.median(sub["mpc"])) if "mpc" in sub else 1.0
            if mpc < mpc_min:
                continue
            best = sub.index[np.argmin(np.abs(sub["frequency_hz"].to_numpy() - fm))]
            rows.append(
                {
                    "frequency_hz": fm,
                    "damping_ratio": float(np.median(sub["damping_ratio"])),
                    "frequency_std_hz": float(np.std(sub["frequency_hz"])),
                    "damping_std": float(np.std(sub["damping_ratio"])),
                    "n_stable_orders": int(n_stable),
                    "mpc": mpc,
                    "n_orders": n_orders,
                }
            )
            shapes.append(real_shape(poles.shapes[best]))
    table = pd.DataFrame(
        rows,
        columns=[
            "frequency_hz",
            "damping_ratio",
            "frequency_std_hz",
            "damping_std",
            "n_stable_orders",
            "mpc",
            "n_orders",
        ],
    )
    table.insert(0, "mode", np.arange(1, len(table) + 1))
    shp = np.array(shapes).T if shapes else np.zeros((len(poles.output_labels), 0))
    return SelectedModes(table, shp, poles.output_labels)

