"""Analyses: functions from result tables to derived tables, and the figures drawn from them.

A study asks for analyses in its config's ``report`` section, by name, with options::

    report:
      selection: {tolerance: 1.0e-5, reference_objective: 1.5933e-5}
      minima: {x_tol: 0.05}

Every analysis is one :class:`Analysis` object in :data:`ANALYSES`: its name,
``tables(tables, **options) -> {name: DataFrame}`` (pure: tables in, tables out),
``figures(tables, out_dir, **options) -> [paths]`` (drawn from the tables only) and optionally
``check_options(**options)`` (InputError for a bad option, called when the config is read,
before any run). A new analysis is a module of this package with those functions and one
line in :data:`ANALYSES`. Report options never change a run's identity: changing them and
running ``gomu report`` keeps every stored run.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from framework.core.errors import InputError
from framework.report.analyses import (
    choices,
    comparison,
    congruence,
    damage_summary,
    minima,
    modes,
    selection,
    sensitivity,
    starts,
    timing,
    truth,
    updating_summary,
)

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Analysis:
    """One analysis: derived tables and figures from a study's tables (module docstring)."""

    name: str
    tables: Callable[..., dict[str, pd.DataFrame]]
    figures: Callable[..., list[Path]]
    #: ``check_options(**options)``: InputError for a bad option when the config is read
    check_options: Callable[..., None] | None = None


ANALYSES: dict[str, Analysis] = {a.name: a for a in (
    Analysis("selection", selection.tables, selection.figures),
    Analysis("minima", minima.tables, minima.figures),
    Analysis("truth", truth.tables, truth.figures),
    Analysis("comparison", comparison.tables, comparison.figures),
    Analysis("sensitivity", sensitivity.tables, sensitivity.figures),
    Analysis("modes", modes.tables, modes.figures),
    Analysis("updating_summary", updating_summary.tables, updating_summary.figures),
    Analysis("choices", choices.tables, choices.figures),
    Analysis("damage_summary", damage_summary.tables, damage_summary.figures, damage_summary.check_options),
    Analysis("congruence", congruence.tables, congruence.figures),
    Analysis("timing", timing.tables, timing.figures),
    Analysis("starts", starts.tables, starts.figures),
)}


def get_analysis(name: str) -> Analysis:
    if name not in ANALYSES:
        raise InputError(f"report.{name}: unknown analysis; known: {sorted(ANALYSES)}")
    return ANALYSES[name]


def check_report(report: dict, allowed_extra: tuple[str, ...] = ()) -> dict:
    """Every key of a ``report`` section names a known analysis (or an allowed figure option),
    its options are a mapping and pass the analysis's ``check_options``."""
    for name, options in report.items():
        if name in allowed_extra:
            continue
        analysis = get_analysis(name)
        if options is not None and not isinstance(options, dict):
            raise InputError(f"report.{name}: options must be a mapping, got {options!r}")
        if analysis.check_options is not None:
            try:
                analysis.check_options(**(options or {}))
            except TypeError as exc:  # an unknown option name
                raise InputError(f"report.{name}: {exc}") from None
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
