"""Interactive 3-D mode shapes as an HTML page (plotly, the optional ``viz`` extra).

``shapes_html(results_dir)`` reads the ``geometry`` and ``mode_shapes`` tables of a results
folder and writes ``shapes_<state>.html``: the undeformed structure and one deformed trace
per model mode, chosen with a slider, elements coloured by group; rotate and zoom in the
browser. Drawn from the tables only, like the static figures.

Why plotly: it is a well-kept library that writes a self-contained page from plain arrays
(no VTK stack as pyvista needs, no live OpenSees domain as opsvis and opstool read), so the
page can be made anywhere from the stored tables. The page loads plotly.js from its CDN
(``include_plotlyjs="cdn"``), which keeps the file small; it is not committed with results.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from framework.core.errors import MissingDependencyError

#: largest drawn translation as a fraction of the structure's largest dimension
DEFORMATION_FRACTION = 0.12


def _segments(geometry: pd.DataFrame, xyz: dict[int, np.ndarray], group: str) -> np.ndarray:
    """Polyline points (with NaN breaks) of every element of ``group``."""
    pts = []
    for nodes, g in zip(geometry["nodes"], geometry["group"].fillna("")):
        if g != group:
            continue
        tags = [int(n) for n in str(nodes).split() if int(n) in xyz]
        if len(tags) < 2:
            continue
        order = tags + [tags[0]] if len(tags) > 2 else tags
        pts += [xyz[t] for t in order] + [np.full(3, np.nan)]
    return np.array(pts).reshape(-1, 3)


def shapes_html(results_dir: str | Path, state: str | None = None, model: str | None = None) -> Path:
    """Write ``shapes_<state>[_<model>].html`` from a results folder's shape tables; returns its path."""
    try:
        import plotly.graph_objects as go
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise MissingDependencyError("the interactive view needs plotly: pip install -e '.[viz]'") from exc
    from framework.core.tables import read_table

    root = Path(results_dir)
    geometry, modes = read_table(root, "geometry"), read_table(root, "mode_shapes")
    if model is not None and "model" in geometry:
        geometry, modes = geometry[geometry["model"] == model], modes[modes["model"] == model]
    state = state or list(dict.fromkeys(modes["state"]))[-1]
    modes = modes[modes["state"] == state]
    nodes = geometry[geometry["kind"] == "node"]
    elements = geometry[geometry["kind"] == "element"]
    base = {int(t): np.array([x, y, z]) for t, x, y, z in zip(nodes["tag"], nodes["x"], nodes["y"], nodes["z"])}
    size = float(np.ptp(np.array(list(base.values())), axis=0).max()) or 1.0
    groups = list(dict.fromkeys(elements["group"].fillna("")))
    fig = go.Figure()
    for g in groups:
        p = _segments(elements, base, g)
        fig.add_trace(go.Scatter3d(x=p[:, 0], y=p[:, 1], z=p[:, 2], mode="lines", name=f"undeformed {g}",
                                   line={"color": "lightgrey", "width": 2}))
    n_fixed = len(fig.data)
    mode_numbers = sorted(modes["mode"].unique())
    for m in mode_numbers:
        d = modes[modes["mode"] == m]
        u = dict(zip(d["node"].astype(int), d[["ux", "uy", "uz"]].to_numpy(float)))
        moved = {t: c + DEFORMATION_FRACTION * size * np.nan_to_num(u.get(t, np.zeros(3))) for t, c in base.items()}
        for g in groups:
            p = _segments(elements, moved, g)
            fig.add_trace(go.Scatter3d(x=p[:, 0], y=p[:, 1], z=p[:, 2], mode="lines", name=g or "structure",
                                       visible=m == mode_numbers[0], line={"width": 4}))
    per_mode = len(groups)
    steps = []
    for k, m in enumerate(mode_numbers):
        visible = [True] * n_fixed + [False] * (len(fig.data) - n_fixed)
        for j in range(per_mode):
            visible[n_fixed + k * per_mode + j] = True
        f = modes.loc[modes["mode"] == m, "f_hz"].iloc[0]
        steps.append({"method": "update", "label": f"{m}: {f:.3f} Hz",
                      "args": [{"visible": visible}, {"title": f"mode {m}, {f:.3f} Hz ({state} parameters)"}]})
    fig.update_layout(sliders=[{"steps": steps, "currentvalue": {"prefix": "model mode "}}],
                      scene={"aspectmode": "data"}, title=f"mode {mode_numbers[0]} ({state} parameters)")
    path = root / f"shapes_{state}{'_' + model if model else ''}.html"
    fig.write_html(path, include_plotlyjs="cdn")
    return path


def all_html(results_dir: str | Path) -> list[Path]:
    """``shapes_html`` for every state and model of a folder with shape tables (none without)."""
    from framework.core.tables import read_table

    root = Path(results_dir)
    try:
        modes = read_table(root, "mode_shapes")
    except FileNotFoundError:
        return []
    if modes.empty:
        return []
    models = list(dict.fromkeys(modes["model"])) if "model" in modes else [None]
    out = []
    for model in models:
        sub = modes if model is None else modes[modes["model"] == model]
        for state in dict.fromkeys(sub["state"]):
            out.append(shapes_html(root, state, model if len(models) > 1 else None))
    return out
