"""Execute one run spec of any kind and return its rows, keyed, for every table.

``execute_run(spec)`` is a pure function of the spec (every random draw comes from the
spec's seed), safe to call in any process. It never raises for a failed run: the error is
recorded as a row of the kind's first table (status "error", the message and the last
frames of the traceback; :func:`framework.study.kinds.base.failure_tables`), so a study goes
on. Every row of every table starts with the run key (run_id, study, kind, label, variant,
seed) and the run's setting columns.
"""

from __future__ import annotations

import logging
import traceback

from framework.study.kinds import get_kind
from framework.study.kinds.base import failure_tables, run_spec

log = logging.getLogger(__name__)


def run_key(spec: dict) -> dict:
    """The columns that identify a run in every table, then its setting columns."""
    key = {k: spec[k] for k in ("run_id", "study", "kind", "label", "variant", "seed")}
    return {**key, **spec.get("columns", {})}


def error_tables(spec: dict, exc: BaseException, tb: str = "") -> dict[str, list[dict]]:
    """The rows of a run that failed as a whole: one row with status 'error' in the run table."""
    return failure_tables(get_kind(spec["kind"]), run_key(spec), exc, tb)


def execute_run(spec: dict) -> dict[str, list[dict]]:
    """Run one spec with its kind; rows keyed by the run."""
    kind = get_kind(spec["kind"])
    try:
        tables = run_spec(kind, spec)
    except (Exception, SystemExit) as exc:  # a failed run is data, not the end of the study
        log.warning("run %s (%s seed %s) failed: %s", spec["run_id"], spec["label"], spec["seed"], exc)
        return error_tables(spec, exc, traceback.format_exc(limit=5))
    key = run_key(spec)
    return {name: [{**key, **row} for row in rows] for name, rows in tables.items()}
