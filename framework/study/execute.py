"""Execute one run spec of any kind and return its rows, keyed, for every table.

``execute_run(spec)`` is a pure function of the spec (every random draw comes from the
spec's seed), safe to call in any process. It never raises for a failed run: the error is
recorded as a row of the kind's first table (status "error", the message and the last
frames of the traceback), so a study goes on. Every row of every table starts with the run
key (run_id, study, kind, label, variant, seed) and the run's setting columns.
"""

from __future__ import annotations

import logging
import traceback

import numpy as np

from framework.study.kinds import get_kind

log = logging.getLogger(__name__)


def run_key(spec: dict) -> dict:
    """The columns that identify a run in every table, then its setting columns."""
    key = {k: spec[k] for k in ("run_id", "study", "kind", "label", "variant", "seed")}
    return {**key, **spec.get("columns", {})}


def error_tables(spec: dict, exc: BaseException, tb: str = "") -> dict[str, list[dict]]:
    """The rows of a run that failed as a whole: one row with status 'error' in the run table."""
    kind = get_kind(spec["kind"])
    row = {**run_key(spec), "objective": np.nan, "n_evaluations": 0, "wall_s": 0.0, "status": "error",
           "error": f"{type(exc).__name__}: {exc}"}
    if tb:
        row["traceback"] = tb
    tables = {t: [] for t in kind.TABLES}
    tables[kind.TABLES[0]] = [row]
    return tables


def execute_run(spec: dict) -> dict[str, list[dict]]:
    """Run one spec with its kind; rows keyed by the run."""
    kind = get_kind(spec["kind"])
    try:
        tables = kind.run(spec)
    except (Exception, SystemExit) as exc:  # a failed run is data, not the end of the study
        log.warning("run %s (%s seed %s) failed: %s", spec["run_id"], spec["label"], spec["seed"], exc)
        return error_tables(spec, exc, traceback.format_exc(limit=5))
    key = run_key(spec)
    return {name: [{**key, **row} for row in rows] for name, rows in tables.items()}
