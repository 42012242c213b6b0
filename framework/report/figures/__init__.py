"""Every figure of gomu, drawn from a results folder's tables only (never from a model or
from in-memory state), one module per subject, each through :mod:`.style` (the one backend
choice, style, resolution and file format; no other module imports matplotlib):

- :mod:`.updating`: an updating study (convergence, parameters, frequencies, validation);
- :mod:`.shapes` and :mod:`.correlation`: mode shapes, MAC, auto-MAC and COMAC of every
  study with shape tables (:func:`shape_figures` below); :mod:`.interactive`: the shapes
  as an HTML page (plotly);
- :mod:`.modes`, :mod:`.sensitivity`, :mod:`.selection`, :mod:`.minima`,
  :mod:`.comparison`, :mod:`.updating_summary`, :mod:`.damage_summary`: the figures of the
  analyses of the same name (:mod:`framework.report.analyses` computes their tables and
  calls these);
- :mod:`.identification`, :mod:`.diagnosis`, :mod:`.posterior`: the figures of the run
  kinds of the same name (a kind's ``figures`` hook calls them).

``shape_figures(out_dir)`` reads the tables written by :mod:`framework.study.shapes`
(``geometry``, ``mode_shapes``, ``sensor_shapes``, ``mac_matrix``, ``comac``) and draws
:mod:`.shapes` (mode shapes, measured over model) and :mod:`.correlation` (MAC, auto-MAC,
COMAC). No model is built, so ``gomu report`` draws them where the model cannot be built.
"""

from __future__ import annotations

import logging
from pathlib import Path

from framework.report.figures.correlation import auto_mac_model_figure, comac_figure, mac_figure
from framework.report.figures.shapes import model_modes_figure, paired_figure

log = logging.getLogger(__name__)


def shape_figures(out_dir: str | Path) -> list[Path]:
    """Every mode-shape and correlation figure the folder's tables support; returns the files."""
    from framework.core.tables import read_tables
    from framework.report.shape_tables import TABLES

    root = Path(out_dir)
    tables = read_tables(root, TABLES)
    if not tables or "mac_matrix" not in tables or tables["mac_matrix"].empty:
        return []
    models = list(dict.fromkeys(tables["mac_matrix"]["model"])) if "model" in tables["mac_matrix"] else [None]
    written = []
    for model in models:
        t = {name: (df[df["model"] == model] if model is not None and "model" in df else df)
             for name, df in tables.items()}
        suffix = f"_{model}" if len(models) > 1 else ""
        written += _draw(root, t, suffix)
    return written


def _draw(root: Path, t: dict, suffix: str) -> list[Path]:
    geometry = t.get("geometry")
    modes, sensors = t.get("mode_shapes"), t.get("sensor_shapes")
    states = list(dict.fromkeys(modes["state"])) if modes is not None and not modes.empty else []
    jobs = []
    if geometry is not None and not geometry.empty and states:
        jobs.append((model_modes_figure, (geometry, modes, root / f"shapes_model{suffix}.png", states[-1])))
    if sensors is not None and not sensors.empty:
        for state in dict.fromkeys(sensors["state"]):
            jobs.append((paired_figure, (geometry, modes, sensors, root / f"shapes_paired_{state}{suffix}.png",
                                         state)))
    if t.get("mac_matrix") is not None and not t["mac_matrix"].empty:
        jobs.append((mac_figure, (t["mac_matrix"], root / f"mac_matrix{suffix}.png")))
        jobs.append((auto_mac_model_figure, (t["mac_matrix"], root / f"auto_mac_model{suffix}.png")))
    if t.get("comac") is not None and not t["comac"].empty:
        jobs.append((comac_figure, (t["comac"], geometry, root / f"comac{suffix}.png")))
    written = []
    for fn, args in jobs:
        try:
            path = fn(*args)
        except Exception as exc:  # a figure must not lose the tables
            log.warning("figure %s of %s failed: %s: %s", fn.__name__, root, type(exc).__name__, exc)
            continue
        if path is not None:
            written.append(Path(path))
    return written


def draw_problem_shapes(problem, states: dict, out_dir: str | Path, structure: str = "") -> list[Path]:
    """For scripts and notebooks: the shape tables of ``problem`` at the named points
    ``{state: theta}`` (physical values) written to ``out_dir`` and their figures drawn."""
    from framework.core.tables import write_table
    from framework.report.shape_tables import TABLES, shape_tables

    root = Path(out_dir)
    root.mkdir(parents=True, exist_ok=True)
    tables = shape_tables(problem, states, structure=structure)
    for name in TABLES:
        write_table(tables[name], root / name)
    return shape_figures(root)
