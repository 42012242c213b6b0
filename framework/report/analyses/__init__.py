"""Analyses: functions from result tables to derived tables, and the figures drawn from them.

A study asks for analyses in its config's ``report`` section, by name, with options::

    report:
      selection: {tolerance: 1.0e-5, reference_objective: 1.5933e-5}
      minima: {x_tol: 0.05}

Every analysis is a module with ``tables(tables, **options) -> {name: DataFrame}`` (pure:
tables in, tables out) and ``figures(tables, out_dir, **options) -> [paths]`` (drawn from
the tables only). The registry maps names to modules, imported only when used. Report
options never change a run's identity: changing them and running ``gomu report`` keeps every
stored run.
"""

from __future__ import annotations

import importlib
import logging
from pathlib import Path
from types import ModuleType

import pandas as pd

from framework.core.errors import InputError

log = logging.getLogger(__name__)

ANALYSES: dict[str, str] = {
    "selection": "framework.report.analyses.selection",
    "minima": "framework.report.analyses.minima",
    "truth": "framework.report.analyses.truth",
    "comparison": "framework.report.analyses.comparison",
    "sensitivity": "framework.report.analyses.sensitivity",
    "modes": "framework.report.analyses.modes",
    "updating_summary": "framework.report.analyses.updating_summary",
    "choices": "framework.report.analyses.choices",
    "damage_summary": "framework.report.analyses.damage_summary",
    "congruence": "framework.report.analyses.congruence",
    "timing": "framework.report.analyses.timing",
    "starts": "framework.report.analyses.starts",
}


def get_analysis(name: str) -> ModuleType:
    if name not in ANALYSES:
        raise InputError(f"report.{name}: unknown analysis; known: {sorted(ANALYSES)}")
    return importlib.import_module(ANALYSES[name])


def check_report(report: dict, allowed_extra: tuple[str, ...] = ()) -> dict:
    """Every key of a ``report`` section names a known analysis (or an allowed figure option)
    and its options are a mapping."""
    for name, options in report.items():
        if name in allowed_extra:
            continue
        get_analysis(name)
        if options is not None and not isinstance(options, dict):
            raise InputError(f"report.{name}: options must be a mapping, got {options!r}")
    return report


def run_analyses(tables: dict[str, pd.DataFrame], report: dict) -> dict[str, pd.DataFrame]:
    """The derived tables of every analysis named in ``report``."""
    out: dict[str, pd.DataFrame] = {}
    for name, options in report.items():
        if name not in ANALYSES:
            continue
        out.update(get_analysis(name).tables(tables, **(options or {})))
    return out


def analysis_figures(tables: dict[str, pd.DataFrame], out_dir: Path, report: dict) -> list[Path]:
    """The figures of every analysis named in ``report`` (a failing figure is logged, skipped)."""
    written: list[Path] = []
    for name, options in report.items():
        if name not in ANALYSES:
            continue
        try:
            written += list(get_analysis(name).figures(tables, out_dir, **(options or {})))
        except Exception as exc:
            log.warning("figures of analysis %s failed: %s", name, exc)
    return written
