"""Run a whole study: plan, skip stored runs (resume), execute, store, consolidate, plot."""

from __future__ import annotations

import logging
from pathlib import Path

import pandas as pd
import yaml

from framework.parallel import map_unordered
from framework.study.config import StudyConfig
from framework.study.execute import error_tables, execute_run
from framework.study.plan import plan
from framework.study.store import ResultStore

log = logging.getLogger(__name__)


def run_study(
    cfg: StudyConfig,
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
    (identified by their spec hash) are kept and skipped.
    """
    out = cfg.output_dir(root)
    store = ResultStore(out)
    specs = plan(cfg)
    preflight(specs)
    store.clean_temp()
    wanted = {s["run_id"] for s in specs}
    if not resume and store.parts.exists():
        for path in store.parts.glob("*.json"):
            path.unlink()
    store.write_config(yaml.safe_dump(cfg.model_dump(mode="json"), sort_keys=False))
    done = store.stored_ids()
    todo = [s for s in specs if s["run_id"] not in done]
    log.info(
        "study %s: %d runs planned, %d stored, %d to run",
        cfg.study,
        len(specs),
        len(specs) - len(todo),
        len(todo),
    )
    backend = backend or cfg.execution.backend
    workers = workers or cfg.execution.workers
    scheduler = scheduler or cfg.execution.scheduler
    show = cfg.execution.progress if progress is None else progress
    bar = _progress(len(todo), cfg.study, show)
    try:
        for i, result in map_unordered(
            execute_run, todo, backend=backend, workers=workers, scheduler=scheduler
        ):
            spec = todo[i]
            if isinstance(result, Exception):
                result = error_tables(spec, result)
            store.write_run(spec["run_id"], result)
            bar.update(1)
    finally:
        bar.close()
    tables = store.consolidate(wanted)
    if figures:
        from framework.plots import report

        report(out)
    return tables


def preflight(specs: list[dict]) -> None:
    """Build every distinct problem of the plan (model, data, parameters, objective) before
    any run starts, so bad input fails early with an InputError naming the field and value."""
    from framework.errors import InputError
    from framework.study.execute import build_problem

    seen = set()
    for spec in specs:
        config = spec["config"]
        key = repr({k: config[k] for k in ("structure", "measured", "validation", "parameters", "objective")})
        if key in seen:
            continue
        seen.add(key)
        try:
            build_problem(config)
            for case in config.get("validation", []):
                build_problem(config, structure_options=case["structure_options"], measured_cfg=case["measured"])
        except InputError as exc:
            raise InputError(f"study {spec['study']!r}: {exc}") from None
        except (KeyError, ValueError, TypeError) as exc:
            raise InputError(f"study {spec['study']!r}: {type(exc).__name__}: {exc}") from None


def _progress(total: int, name: str, show: bool):
    from tqdm.auto import tqdm

    return tqdm(total=total, desc=f"{name} runs", unit="run", disable=not show or total == 0)


def summary(tables: dict[str, pd.DataFrame]) -> pd.DataFrame:
    """Per label and variant: runs, median/min/max objective, mean evaluations, status counts."""
    runs = tables["runs"]
    if runs.empty:
        return runs
    g = runs.groupby(["label", "variant"], sort=False)
    return pd.DataFrame(
        {
            "runs": g.size(),
            "objective_median": g["objective"].median(),
            "objective_min": g["objective"].min(),
            "objective_max": g["objective"].max(),
            "evaluations_mean": g["n_evaluations"].mean().round(0),
            "wall_s_mean": g["wall_s"].mean().round(3),
            "errors": g["status"].apply(lambda s: int((s == "error").sum())),
        }
    ).reset_index()
