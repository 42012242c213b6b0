"""Post-run stage of ``gomu run``: mode-shape and correlation tables of a study.

After the runs are consolidated (also on ``--resume`` with nothing left to run), an
``updating`` study gets the tables of :mod:`framework.report.shape_tables` at two points of its
best run (lowest objective among runs that did not fail): ``initial`` (the parameters'
initial values) and ``updated`` (that run's parameters), on that run's structure and base
measured data; a study comparing structures gets them for the best run of each (column
``model``: the structure's name). An ``analysis`` study gets them at each of its points (the
variant with the most successful points, per structure). A ``damage`` study (the beam) gets
them per damaged state for its best estimate (:func:`damage_problems`). Other kinds get none. The
model's geometry comes from the structure's descriptor (its ``geometry`` hook, else the model's
own ``geometry`` method or OpenSees domain, :mod:`framework.models.geometry`): a user's
``module:function`` model takes the same path as a built-in. The figures are drawn from the
written tables only (:mod:`framework.report.figures`), so ``gomu report`` needs no model.

A failure here (a model that cannot be built, say) is logged and leaves the study's tables
untouched.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pandas as pd

from framework.core.tables import write_table
from framework.report.shape_tables import TABLES, shape_tables

log = logging.getLogger(__name__)

KINDS = ("updating", "analysis", "damage")


def shape_states(cfg, tables: dict[str, pd.DataFrame]) -> list[tuple[dict, dict[str, np.ndarray]]]:
    """[(task, {state: theta})] of a study's tables, one per structure its runs use (a study
    comparing two models, e.g. the detailed and the 3-DOF lab frame, gets both)."""
    from framework.study.kinds.updating import build_problem
    from framework.study.plan import plan

    runs = tables.get("runs") if cfg.kind == "updating" else tables.get("points")
    params = tables.get("parameters")
    if runs is None or runs.empty or params is None or params.empty:
        return []
    objective = pd.to_numeric(runs["objective"], errors="coerce")
    ok = runs[~runs["status"].isin(["failed", "error"]) & np.isfinite(objective)]
    if ok.empty:
        return []
    planned = plan(cfg)
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
        if cfg.kind == "updating":
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
        if cfg.kind == "updating":
            states["initial"] = np.asarray(problem.parameters.initial, float)
        for state, rid in chosen:
            values = params[params["run_id"] == rid].set_index("parameter")["value"]
            if set(names) <= set(values.index):
                states[state] = np.array([float(values[n]) for n in names])
        found.append((task, states))
    return found


def damage_problems(cfg, tables: dict[str, pd.DataFrame]) -> list[tuple[str, object, dict[str, np.ndarray]]]:
    """Beam damage studies (kind ``damage``): per damaged state, the 10-element model against
    that state's measurement of the best estimate (lowest objective of the first planned
    variant, e.g. the SPEC's 3 % noise), at the intact ratios (``initial``) and at that
    method's own updated ratios (``updated``)."""
    from framework.structures.beam import model as beam
    from framework.study.kinds import damage
    from framework.study.plan import plan
    from framework.updating.problem import UpdatingProblem

    runs, states, elements = (tables.get(n) for n in ("runs", "states", "elements"))
    if runs is None or states is None or elements is None or states.empty or elements.empty:
        return []
    specs = plan(cfg)
    first_variant = specs[0]["variant"]
    by_key = {(s["label"], s["variant"], s["seed"]): s for s in specs}
    keyed = runs.set_index("run_id")
    out = []
    for state in damage.DAMAGED:
        rows = states[(states["state"] == state) & ~states["status"].isin(["failed", "error"])
                      & np.isfinite(pd.to_numeric(states["objective"], errors="coerce"))]
        rows = rows[rows["run_id"].map(keyed["variant"]) == first_variant] if "variant" in keyed else rows
        if rows.empty:
            continue
        best = rows.sort_values(["objective", "run_id", "method"]).iloc[0]
        run = keyed.loc[best["run_id"]]
        spec = by_key.get((run["label"], run["variant"], int(run["seed"])))
        if spec is None:
            continue
        e = elements[(elements["run_id"] == best["run_id"]) & (elements["method"] == best["method"])
                     & (elements["state"] == state)].sort_values("element")
        task = spec["task"]
        model = beam.make_model(n_modes=max(7, int(task["n_modes"])))
        problem = UpdatingProblem(model, damage.measurements(task, spec["seed"])[state])
        ratios = e["updated_ratio"].to_numpy(float)
        if ratios.size != len(problem.parameters):
            continue
        out.append((f"beam_{state}", problem, {"initial": np.ones(ratios.size), "updated": ratios}))
    return out


def write_shape_tables(out: Path, tables: dict[str, pd.DataFrame], cfg) -> list[Path]:
    """Write the shape tables of a study into ``out``; returns the files (none on failure)."""
    if cfg.kind not in KINDS:
        return []
    from framework.study.kinds.updating import build_problem
    from framework.study.structure_hooks import geometry_of

    try:
        parts: dict[str, list[pd.DataFrame]] = {name: [] for name in TABLES}
        if cfg.kind == "damage":
            found = [(name, problem, states, None) for name, problem, states in damage_problems(cfg, tables)]
        else:
            found = [(task["structure"]["name"], build_problem(task), states, geometry_of(task["structure"]["name"]))
                     for task, states in shape_states(cfg, tables)]
        for model, problem, states, geometry in found:
            shapes = shape_tables(problem, states, structure=model, geometry=geometry)
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
