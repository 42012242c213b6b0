"""What every run kind is and shares: the :class:`Kind` object, its failure rows, the runner of
its model evaluations (with the isolation of user code), its preflight and its report check.

A run kind is one :class:`Kind` object, registered in :data:`framework.study.kinds.KINDS`.
It says what a study of that kind reads (``config``: a subclass of
:class:`~framework.study.schema.StudyHeader`), which tables its runs write (``tables``: the
first holds one row per run with a ``status`` of :class:`~framework.core.status.Status`),
how a study becomes runs (``plan_runs``) and what one run does (``run``); the rest is
optional. The engine (:mod:`framework.study.runner`, :mod:`framework.study.execute`) does
everything the kinds share, the same way for each:

- **failure rows**: a run that raises becomes one row of the first table with status
  ``error`` (:func:`failure_tables`); a kind's own failures are rows built by :func:`failure`;
- **model evaluations**: a kind with ``evaluates_model`` gets ``run(spec, runner)``, the
  runner built by :func:`evaluation_runner` from the spec's ``execution`` section, isolated
  in a worker process when ``user_code(task)`` says its model is user code
  (``execution.isolate: auto``);
- **preflight**: :func:`preflight` checks each distinct input (``preflight_key``) with the
  kind's ``preflight`` before any run starts; every error becomes one InputError naming the
  study;
- **report options**: :func:`check_report` checks a config's ``report`` section against the
  kind's ``report`` (the analyses registry, a pydantic model, or none) when the config is read;
- **mode shapes**: a kind with a ``shapes`` hook gets the mode-shape tables of
  :mod:`framework.study.shapes` after its runs.
"""

from __future__ import annotations

import contextlib
import json
from collections.abc import Callable, Hashable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd
from pydantic import BaseModel, ValidationError

from framework.core.errors import InputError
from framework.core.status import Status, error_text
from framework.study.schema import StudyHeader, _short, evaluation_isolation

#: ``Kind.report`` of a kind whose ``report`` section names analyses
#: (:data:`framework.report.analyses.ANALYSES`) with their options
ANALYSES = "analyses"


@dataclass(frozen=True)
class Kind:
    """One run kind: its schema, its tables, how it plans and runs, and its optional hooks."""

    #: the ``kind:`` of its configs
    name: str
    #: the pydantic schema of its studies (a StudyHeader subclass; unknown keys rejected)
    config: type[StudyHeader]
    #: the tables its runs write; the first holds one row per run (status, error, ...)
    tables: tuple[str, ...]
    #: ``plan_runs(cfg, sweep_values) -> [{"label", "seed", "task", "columns", "relevant"}]``:
    #: ``task`` is everything a run needs (picklable; its identity is hashed into the run id),
    #: ``columns`` its setting columns, ``relevant`` the sweep keys that change it (optional)
    plan_runs: Callable[[StudyHeader, dict[str, Any]], list[dict]]
    #: ``run(spec) -> {table: [row]}``, or ``run(spec, runner)`` with ``evaluates_model``;
    #: a failed result is a row (:func:`failure`), an exception becomes the engine's failure row
    run: Callable[..., dict[str, list[dict]]]
    #: ``check(cfg, source, base_dir)``: checks beyond the schema when the config is read
    #: (data files); imports no code the config names
    check: Callable[[StudyHeader, str, Path | None], None] | None = None
    #: ``identity(task) -> dict``: the part of a task that determines its result (plain data;
    #: default the task itself)
    identity: Callable[[dict], dict] | None = None
    #: ``preflight(spec, build_references)``: check one spec's inputs (build its model, read its
    #: data), raising InputError; without ``build_references`` import no code named in the config
    preflight: Callable[[dict, bool], None] | None = None
    #: specs with equal keys share their inputs and are checked once (default: each spec)
    preflight_key: Callable[[dict], Hashable] | None = None
    #: the kind evaluates the structure's model through the run's evaluation runner
    evaluates_model: bool = False
    #: does a task's model come from user code (``module:function``)? (``isolate: auto``)
    user_code: Callable[[dict], bool] = field(default=lambda task: False)
    #: the ``report`` section: ANALYSES (analysis names and options), a pydantic model, or None
    report: str | type[BaseModel] | None = None
    #: ``analyses(tables, report) -> {name: DataFrame}``: derived tables, from the tables only
    analyses: Callable[[dict, dict], dict[str, pd.DataFrame]] | None = None
    #: ``figures(tables, out_dir, report) -> [Path]``: figures, from the tables only
    figures: Callable[[dict, Path, dict], list[Path]] | None = None
    #: ``shapes(cfg, tables, specs) -> [(model name, problem, {state: theta})]``: the points whose
    #: mode-shape tables follow the runs (:mod:`framework.study.shapes`)
    shapes: Callable[[StudyHeader, dict, list[dict]], list[tuple]] | None = None

    def identity_of(self, task: dict) -> dict:
        return self.identity(task) if self.identity is not None else task


# ---- failure rows -----------------------------------------------------------------------------
def failure(error: BaseException | str, status: Status = Status.FAILED) -> dict[str, Any]:
    """The ``status`` and ``error`` columns of a row without a usable result; an exception is
    written ``"<type>: <message>"``."""
    return {"status": status, "error": error if isinstance(error, str) else error_text(error)}


def failure_tables(kind: Kind, key: dict, exc: BaseException, tb: str = "") -> dict[str, list[dict]]:
    """The rows of a run that raised: one row of the kind's first table, status ``error``,
    keyed by the run (``key``), every other table empty."""
    row = {**key, "objective": float("nan"), "n_evaluations": 0, "wall_s": 0.0, **failure(exc, Status.ERROR)}
    if tb:
        row["traceback"] = tb
    tables: dict[str, list[dict]] = {t: [] for t in kind.tables}
    tables[kind.tables[0]] = [row]
    return tables


# ---- model evaluations ------------------------------------------------------------------------
@contextlib.contextmanager
def evaluation_runner(execution: dict, user_code: bool = False) -> Iterator[Callable]:
    """The runner of a run's model evaluations from its ``execution`` section, released on exit:
    backend (serial, processes, dask), isolation of the model in a worker process
    (``isolate: auto``: when the model is ``user_code``) and the per-evaluation timeout
    (:func:`framework.study.schema.evaluation_isolation`,
    :func:`framework.execution.parallel.make_evaluation_runner`)."""
    from framework.execution.parallel import make_evaluation_runner

    isolate, timeout_s = evaluation_isolation(execution, user_code)
    runner, close = make_evaluation_runner(
        execution.get("evaluation_backend", "serial"),
        workers=execution.get("workers", 2),
        isolate=isolate,
        timeout_s=timeout_s,
        scheduler=execution.get("scheduler"),
    )
    try:
        yield runner
    finally:
        close()


def run_spec(kind: Kind, spec: dict) -> dict[str, list[dict]]:
    """One run of ``kind``: with ``evaluates_model``, through the runner of the spec's execution
    section (user code isolated by default)."""
    if not kind.evaluates_model:
        return kind.run(spec)
    with evaluation_runner(spec.get("execution", {}), kind.user_code(spec["task"])) as runner:
        return kind.run(spec, runner)


# ---- preflight --------------------------------------------------------------------------------
def preflight(kind: Kind, specs: list[dict], build_references: bool = True) -> None:
    """Check every distinct input of the plan before any run starts: the kind's ``preflight``
    once per ``preflight_key``. Any error becomes an InputError ``study '<name>': ...``."""
    if kind.preflight is None:
        return
    seen: set = set()
    for spec in specs:
        if kind.preflight_key is not None:
            key = kind.preflight_key(spec)
            if key in seen:
                continue
            seen.add(key)
        try:
            kind.preflight(spec, build_references)
        except InputError as exc:
            raise InputError(f"study {spec['study']!r}: {exc}") from None
        except (KeyError, ValueError, TypeError) as exc:
            raise InputError(f"study {spec['study']!r}: {error_text(exc)}") from None


def task_key(spec: dict, keys: tuple[str, ...]) -> str:
    """A preflight key: the task's ``keys`` as canonical JSON."""
    return json.dumps({k: spec["task"][k] for k in keys}, sort_keys=True, default=str)


# ---- report options ---------------------------------------------------------------------------
def check_report(kind: Kind, report: dict) -> None:
    """Check a config's ``report`` section against the kind's ``report``; InputError
    ``report.<key>: <problem>``."""
    if kind.report == ANALYSES:
        from framework.report.analyses import check_report as check_analyses

        check_analyses(report)
    elif kind.report is None:
        if report:
            raise InputError(f"report: kind {kind.name!r} has no report options, got {sorted(report)}")
    else:
        try:
            kind.report.model_validate(report)
        except ValidationError as exc:
            first = exc.errors()[0]
            loc = ".".join(str(p) for p in first["loc"])
            msg = " ".join(first["msg"].removeprefix("Value error, ").split())
            if first["type"] == "extra_forbidden":
                msg = "unknown key" + (f"; known: {sorted(kind.report.model_fields)}" if len(first["loc"]) == 1 else "")
            value = first.get("input")
            shown = "" if isinstance(value, dict) else f" (value: {_short(value)})"
            raise InputError(f"report.{loc}: {msg}{shown}") from None
