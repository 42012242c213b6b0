"""Run a whole study of any kind: plan, check, skip stored runs, execute, store, then derive.

plan -> check the inputs (the kind's preflight) -> claim the output folder -> execute the
runs not stored yet (serial, processes or Dask) -> one atomic part per finished run ->
consolidate the tables -> mode-shape tables (:mod:`framework.study.shapes`) -> analyses
(table -> table) -> figures (from the tables).
``report(results_dir)`` redoes the last two from the stored tables and config alone.
"""

from __future__ import annotations

import logging
import re
from pathlib import Path

import pandas as pd
import yaml

from framework.core.errors import InputError
from framework.core.provenance import write_provenance
from framework.core.status import Status
from framework.core.tables import read_tables, write_table
from framework.core.textio import read_text_file
from framework.execution.parallel import dask_client, map_unordered
from framework.report.figures import shape_figures
from framework.study.execute import error_tables, execute_run
from framework.study.kinds import base, get_kind
from framework.study.plan import plan
from framework.study.schema import StudyHeader
from framework.study.shapes import write_shape_tables
from framework.study.store import ResultStore

log = logging.getLogger(__name__)


def preflight(cfg: StudyHeader, specs: list[dict], build_references: bool = True) -> None:
    """The kind's checks of every distinct input before any run starts (InputError naming the
    config file and the study; :func:`framework.study.kinds.base.preflight`).
    ``build_references=False``: do not import code the config names (``gomu validate``)."""
    try:
        base.preflight(get_kind(cfg.kind), specs, build_references=build_references)
    except InputError as exc:  # name the config file too, not only the data file or field
        raise _named(cfg, exc) from None


def _named(cfg: StudyHeader, exc: InputError) -> InputError:
    """``exc`` with the config file it came from in front (if known and not named yet)."""
    source = getattr(cfg, "_source", "")
    return InputError(f"{source}: {exc}") if source and not str(exc).startswith(source) else exc


def run_study(
    cfg: StudyHeader,
    *,
    resume: bool = False,
    root: Path | None = None,
    figures: bool = True,
    backend: str | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool | None = None,
    shapes: bool | None = None,
) -> dict[str, pd.DataFrame]:
    """Execute every planned run not yet stored and return the consolidated tables.

    Without ``resume`` the study's stored runs are discarded first. With it, stored runs
    (identified by their run id) are kept and skipped. A folder holding another study's
    results is refused, never overwritten. ``shapes`` (default: as ``figures``) writes the
    mode-shape tables of :mod:`framework.study.shapes` (it builds the model again).
    """
    kind = get_kind(cfg.kind)
    out = cfg.output_dir(root)
    store = ResultStore(out)
    specs = plan(cfg)
    preflight(cfg, specs)
    backend = backend or cfg.execution.backend
    workers = workers or cfg.execution.workers
    scheduler = scheduler or cfg.execution.scheduler
    # a scheduler that cannot be reached is an input error before anything stored is touched
    try:
        client = dask_client(scheduler, workers) if backend == "dask" and scheduler else None
    except InputError as exc:
        raise _named(cfg, exc) from None
    try:
        try:
            store.claim(cfg.study)
        except InputError as exc:
            raise _named(cfg, exc) from None
        store.clean_temp()
        wanted = {s["run_id"] for s in specs}
        if not resume:
            store.discard()
        store.write_config(yaml.safe_dump(cfg.model_dump(mode="json"), sort_keys=False))
        write_provenance(out)
        done = store.stored_ids()
        todo = [s for s in specs if s["run_id"] not in done]
        log.info("study %s: %d runs planned, %d stored, %d to run", cfg.study, len(specs), len(specs) - len(todo),
                 len(todo))
        show = cfg.execution.progress if progress is None else progress
        bar = _progress(len(todo), cfg.study, show)
        try:
            for i, result in map_unordered(execute_run, todo, backend=backend, workers=workers, client=client):
                spec = todo[i]
                if isinstance(result, BaseException):
                    result = error_tables(spec, result)
                store.write_run(spec["run_id"], result, study=cfg.study, kind=cfg.kind)
                bar.update(1)
        finally:
            bar.close()
    finally:
        if client is not None:
            client.close()
    tables = store.consolidate(wanted, kind.tables)
    if (figures if shapes is None else shapes):
        write_shape_tables(out, tables, cfg, kind, specs)  # mode shapes and MAC of the initial and best model
    derive(out, tables, cfg, figures=figures)
    return tables


def derive(out: Path, tables: dict[str, pd.DataFrame], cfg: StudyHeader, figures: bool = True) -> list[Path]:
    """Analyses (derived tables, written next to the run tables) and figures; returns the files.

    A failing analysis or figure is logged and skipped: it never loses the tables.
    """
    kind = get_kind(cfg.kind)
    written: list[Path] = []
    counts = failure_counts(tables.get("runs", pd.DataFrame()))
    if not counts.empty:
        write_table(counts, out / "failures")
        written.append(out / "failures.csv")
    if kind.analyses is not None:
        try:
            derived = kind.analyses(tables, cfg.report)
        except InputError:
            raise
        except Exception as exc:
            log.warning("analyses of %s failed: %s", out, exc)
            derived = {}
        for name, df in derived.items():
            write_table(df, out / name)
            written.append(out / f"{name}.csv")
            tables = {**tables, name: df}
    if figures and kind.figures is not None:
        try:
            written += list(kind.figures(tables, out, cfg.report))
        except Exception as exc:
            log.warning("figures of %s failed: %s", out, exc)
    if figures:
        written += shape_figures(out)
    return written


def report(results_dir: str | Path, shapes: bool = False) -> list[Path]:
    """Redo the analyses and figures of a results folder from its tables and config.yaml;
    ``shapes``: first (re)write the mode-shape tables (builds the model)."""
    from framework.study.config import validate

    root = Path(results_dir)
    if not root.is_dir():
        raise InputError(f"results folder not found: {root}")
    config_path = root / "config.yaml"
    if not config_path.exists():
        raise InputError(f"{root}: no config.yaml: not a results folder of gomu run")
    text = read_text_file(config_path, what="results config")  # size limit, UTF-8, not a folder
    try:
        data = yaml.safe_load(text)  # written by gomu run with yaml.safe_dump
    except (yaml.YAMLError, RecursionError) as exc:
        raise InputError(f"{config_path}: cannot be read ({type(exc).__name__})") from None
    cfg = validate(data, source=str(config_path))
    kind = get_kind(cfg.kind)
    tables = read_tables(root, kind.tables)
    if not tables or all(df.empty for df in tables.values()):
        raise InputError(f"{root}: no result tables to report on")
    if not (root / "provenance.json").exists():
        write_provenance(root, by="report")
    if shapes:
        try:
            specs = plan(cfg)
        except InputError as exc:  # the shapes are an aid: the tables stay as they are
            log.warning("mode-shape tables of %s not written: %s", root, exc)
        else:
            write_shape_tables(root, tables, cfg, kind, specs)
    return derive(root, tables, cfg)


#: one entry of a run's ``failures`` text: "<reason> x<count> (<example message>)"
_FAILURE_ENTRY = re.compile(r"(?:^|; )([A-Za-z0-9_]+) x([0-9]+) \(")


def failure_counts(runs: pd.DataFrame) -> pd.DataFrame:
    """Failed evaluations by reason: per label, variant and reason, the failed evaluations
    (``n_failed``) and the runs that had any (``n_runs``), from the runs table's ``failures``
    column (written by the evaluator as ``reason xN (example); ...``). Empty without failures."""
    columns = ["label", "variant", "reason", "n_failed", "n_runs"]
    if runs.empty or "failures" not in runs or not {"label", "variant"} <= set(runs):
        return pd.DataFrame(columns=columns)
    rows = []
    for label, variant, text in zip(runs["label"], runs["variant"], runs["failures"]):
        if isinstance(text, str):
            rows += [(label, variant, m.group(1), int(m.group(2))) for m in _FAILURE_ENTRY.finditer(text)]
    if not rows:
        return pd.DataFrame(columns=columns)
    df = pd.DataFrame(rows, columns=columns[:4])
    g = df.groupby(["label", "variant", "reason"], sort=True)["n_failed"]
    return g.agg(n_failed="sum", n_runs="size").reset_index()


def _progress(total: int, name: str, show: bool):
    from tqdm.auto import tqdm

    return tqdm(total=total, desc=f"{name} runs", unit="run", disable=not show or total == 0)


def summary(tables: dict[str, pd.DataFrame]) -> pd.DataFrame:
    """Per label and variant: runs, median/min/max objective, mean evaluations, status counts."""
    runs = next(iter(tables.values()), pd.DataFrame()) if "runs" not in tables else tables["runs"]
    if runs.empty or "label" not in runs:
        return pd.DataFrame()
    g = runs.groupby(["label", "variant"], sort=False)
    out = {"runs": g.size()}
    if "objective" in runs:
        out |= {"objective_median": g["objective"].median(), "objective_min": g["objective"].min(),
                "objective_max": g["objective"].max()}
    if "n_evaluations" in runs:
        out["evaluations_mean"] = g["n_evaluations"].mean().round(0)
    if "wall_s" in runs:
        out["wall_s_mean"] = g["wall_s"].mean().round(3)
    if "status" in runs:
        out["failed"] = g["status"].apply(lambda s: int((s == Status.FAILED).sum()))
        out["errors"] = g["status"].apply(lambda s: int((s == Status.ERROR).sum()))
    return pd.DataFrame(out).reset_index()
