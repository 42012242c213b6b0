"""Post-run stage of ``gomu run``: mode-shape and correlation tables of a study.

After the runs are consolidated (also on ``--resume`` with nothing left to run), a kind with a
``shapes`` hook (:class:`framework.study.kinds.base.Kind`) names the points whose tables of
:mod:`framework.report.shape_tables` are written: an ``updating`` study at two points of its
best run (lowest objective among runs that did not fail): ``initial`` (the parameters'
initial values) and ``updated`` (that run's parameters), on that run's structure and base
measured data; a study comparing structures gets them for the best run of each (column
``model``: the structure's name). An ``analysis`` study gets them at each of its points (the
variant with the most successful points, per structure); both through :func:`shape_states`.
A ``damage`` study (the beam) gets them per damaged state for its best estimate (its own
hook). Other kinds have no hook and get none. The model's geometry comes from the structure's
descriptor (its ``geometry`` hook, else the model's own ``geometry`` method or its OpenSees
domain, :mod:`framework.models.geometry`): a user's ``module:function`` model takes the same
path as a built-in. The figures are drawn from the written tables only
(:mod:`framework.report.figures`), so ``gomu report`` needs no model.

A failure here (a model that cannot be built, say) is logged and leaves the study's tables
untouched.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pandas as pd

from framework.core.status import FAILURES
from framework.core.tables import write_table
from framework.report.shape_tables import TABLES, shape_tables

log = logging.getLogger(__name__)


def shape_states(tables: dict[str, pd.DataFrame], planned: list[dict], build_problem, best_run: bool
                 ) -> list[tuple[str, object, dict[str, np.ndarray]]]:
    """[(structure name, problem, {state: theta})] of a study's tables, one per structure its
    runs use (a study comparing two models, e.g. the detailed and the 3-DOF lab frame, gets
    both). ``best_run``: the best run's ``initial`` and ``updated`` points (table ``runs``),
    else every point of the variant with the most points (table ``points``); ``planned``: the
    study's run specs, ``build_problem(task)``: the problem of a task."""
    runs = tables.get("runs") if best_run else tables.get("points")
    params = tables.get("parameters")
    if runs is None or runs.empty or params is None or params.empty:
        return []
    objective = pd.to_numeric(runs["objective"], errors="coerce")
    ok = runs[~runs["status"].isin(FAILURES) & np.isfinite(objective)]
    if ok.empty:
        return []
    by_name = {(s["label"], s["variant"], s["seed"]): s for s in planned}
    specs = {s["run_id"]: s for s in planned}
    for _, r in ok.iterrows():  # runs stored by an earlier version of the code: same label, variant, seed
        key = (r["label"], r["variant"], int(r["seed"]))
        if r["run_id"] not in specs and key in by_name:
            specs[r["run_id"]] = by_name[key]
    ok = ok[ok["run_id"].isin(specs)]
    structure = ok["structure"] if "structure" in ok else pd.Series("", index=ok.index)
    found = []
    for _, group in ok.groupby(structure, sort=False):
        if best_run:
            best = group.sort_values(["objective", "run_id"]).iloc[0]
            chosen = [("updated", best["run_id"])]
            task = specs[best["run_id"]]["task"]
        else:  # the variant with the most points (e.g. initial and updated), the first of equals
            counts = group.groupby("variant", sort=False).size()
            variant = counts.idxmax()
            rows = group[group["variant"] == variant]
            chosen = [(str(r["label"]), r["run_id"]) for _, r in rows.iterrows()]
            task = specs[rows["run_id"].iloc[0]]["task"]
        problem = build_problem(task)
        names = problem.parameters.names
        states: dict[str, np.ndarray] = {}
        if best_run:
            states["initial"] = np.asarray(problem.parameters.initial, float)
        for state, rid in chosen:
            values = params[params["run_id"] == rid].set_index("parameter")["value"]
            if set(names) <= set(values.index):
                states[state] = np.array([float(values[n]) for n in names])
        found.append((task["structure"]["name"], problem, states))
    return found


def write_shape_tables(out: Path, tables: dict[str, pd.DataFrame], cfg, kind, specs: list[dict]) -> list[Path]:
    """Write the shape tables of a study into ``out`` at the points of its kind's ``shapes``
    hook; returns the files (none for a kind without the hook, none on failure)."""
    if kind.shapes is None:
        return []
    from framework.study.structure_hooks import geometry_of

    try:
        parts: dict[str, list[pd.DataFrame]] = {name: [] for name in TABLES}
        found = kind.shapes(cfg, tables, specs)
        for model, problem, states in found:
            shapes = shape_tables(problem, states, structure=model, geometry=geometry_of(model))
            for name in TABLES:
                parts[name].append(shapes[name].assign(model=model) if not shapes[name].empty else shapes[name])
        if not parts["mac_matrix"]:
            return []
        shapes = {name: pd.concat(dfs, ignore_index=True) for name, dfs in parts.items()}
    except Exception as exc:  # the figures are an aid; the study's tables stay as they are
        log.warning("mode-shape tables of %s not written: %s: %s", out, type(exc).__name__, exc)
        return []
    written = []
    for name in TABLES:
        write_table(shapes[name], Path(out) / name)
        written.append(Path(out) / f"{name}.csv")
    return written
