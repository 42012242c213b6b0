"""Run a whole study of any kind: plan, check, skip stored runs, execute, store, then derive.

plan -> check the inputs (the kind's preflight) -> claim the output folder -> execute the
runs not stored yet (serial, processes or Dask) -> one atomic part per finished run ->
consolidate the tables -> mode-shape tables (:mod:`framework.shapes.stage`) -> analyses
(table -> table) -> figures (from the tables).
``report(results_dir)`` redoes the last two from the stored tables and config alone.
"""

from __future__ import annotations

import logging
from pathlib import Path

import pandas as pd
import yaml

from framework.errors import InputError
from framework.figures import shape_figures
from framework.parallel import map_unordered
from framework.provenance import write_provenance
from framework.shapes.stage import write_shape_tables
from framework.study.execute import error_tables, execute_run
from framework.study.kinds import get_kind
from framework.study.plan import plan
from framework.study.schema import StudyHeader
from framework.study.store import ResultStore
from framework.tables import read_tables, write_table

log = logging.getLogger(__name__)


def preflight(cfg: StudyHeader, specs: list[dict], build_references: bool = True) -> None:
    """The kind's checks of every distinct input before any run starts (InputError).
    ``build_references=False``: do not import code the config names (``gomu validate``)."""
    check = getattr(get_kind(cfg.kind), "preflight", None)
    if check is not None:
        check(specs, build_references=build_references)


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
) -> dict[str, pd.DataFrame]:
    """Execute every planned run not yet stored and return the consolidated tables.

    Without ``resume`` the study's stored runs are discarded first. With it, stored runs
    (identified by their run id) are kept and skipped. A folder holding another study's
    results is refused, never overwritten.
    """
    kind = get_kind(cfg.kind)
    out = cfg.output_dir(root)
    store = ResultStore(out)
    specs = plan(cfg)
    preflight(cfg, specs)
    store.claim(cfg.study)
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
    backend = backend or cfg.execution.backend
    workers = workers or cfg.execution.workers
    scheduler = scheduler or cfg.execution.scheduler
    show = cfg.execution.progress if progress is None else progress
    bar = _progress(len(todo), cfg.study, show)
    try:
        for i, result in map_unordered(execute_run, todo, backend=backend, workers=workers, scheduler=scheduler):
            spec = todo[i]
            if isinstance(result, BaseException):
                result = error_tables(spec, result)
            store.write_run(spec["run_id"], result, study=cfg.study, kind=cfg.kind)
            bar.update(1)
    finally:
        bar.close()
    tables = store.consolidate(wanted, kind.TABLES)
    write_shape_tables(out, tables, cfg)  # mode shapes and MAC of the initial and best model
    derive(out, tables, cfg, figures=figures)
    return tables


def derive(out: Path, tables: dict[str, pd.DataFrame], cfg: StudyHeader, figures: bool = True) -> list[Path]:
    """Analyses (derived tables, written next to the run tables) and figures; returns the files.

    A failing analysis or figure is logged and skipped: it never loses the tables.
    """
    kind = get_kind(cfg.kind)
    written: list[Path] = []
    analyses = getattr(kind, "analyses", None)
    if analyses is not None:
        try:
            derived = analyses(tables, cfg.report)
        except InputError:
            raise
        except Exception as exc:
            log.warning("analyses of %s failed: %s", out, exc)
            derived = {}
        for name, df in derived.items():
            write_table(df, out / name)
            written.append(out / f"{name}.csv")
            tables = {**tables, name: df}
    draw = getattr(kind, "figures", None)
    if figures and draw is not None:
        try:
            written += list(draw(tables, out, cfg.report))
        except Exception as exc:
            log.warning("figures of %s failed: %s", out, exc)
    if figures:
        written += shape_figures(out)
    return written


def report(results_dir: str | Path) -> list[Path]:
    """Redo the analyses and figures of a results folder from its tables and config.yaml."""
    from framework.study.config import validate

    root = Path(results_dir)
    if not root.is_dir():
        raise InputError(f"results folder not found: {root}")
    config_path = root / "config.yaml"
    if not config_path.exists():
        raise InputError(f"{root}: no config.yaml: not a results folder of gomu run")
    try:
        data = yaml.safe_load(config_path.read_text(encoding="utf-8"))
    except (yaml.YAMLError, UnicodeDecodeError) as exc:
        raise InputError(f"{config_path}: cannot be read ({type(exc).__name__})") from None
    cfg = validate(data, source=str(config_path))
    kind = get_kind(cfg.kind)
    tables = read_tables(root, kind.TABLES)
    if not tables or all(df.empty for df in tables.values()):
        raise InputError(f"{root}: no result tables to report on")
    return derive(root, tables, cfg)


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
        out["failed"] = g["status"].apply(lambda s: int((s == "failed").sum()))
        out["errors"] = g["status"].apply(lambda s: int((s == "error").sum()))
    return pd.DataFrame(out).reset_index()
