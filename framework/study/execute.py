"""Execute one run spec: build the problem, run the optimizer, return tidy rows.

``execute_run(spec)`` is a pure function of the spec (every random draw comes from the
spec's seed), safe to call in any process. It never raises for a failed run: the error
is recorded in the ``runs`` row (status "error") so a study goes on.

Tables (one list of row dicts each):
- runs: one row per run (study, structure, label, algorithm, variant, seed, objective,
  n_evaluations, n_iterations, wall_s, status, error, n_failed_evaluations, failures, ...)
- parameters: one row per run and parameter (parameter, unit, initial, lower, upper, value, ratio)
- modes: one row per run, case and measured mode (case, mode, f_measured_hz, f_model_hz,
  error_pct, mac, matched)
- history: best objective so far, at every evaluation where it improved and the last one
  (the full step curve is recoverable from these rows)
"""

from __future__ import annotations

import logging
import traceback
from typing import Any

import numpy as np

from framework.errors import ModelEvaluationError
from framework.measurements import MeasuredModes
from framework.measurements import load as load_measured
from framework.models.registry import builtin_measured, make_structure
from framework.objectives import ObjectiveSpec
from framework.optimizers import Budget, run_optimizer
from framework.parameters import ParameterSet
from framework.problem import UpdatingProblem

log = logging.getLogger(__name__)

TABLES = ("runs", "parameters", "modes", "history", "extra")


def measured_from(cfg: dict) -> MeasuredModes:
    m = (
        load_measured(cfg["file"])
        if cfg.get("file")
        else builtin_measured(cfg["builtin"], cfg.get("case", "base"))
    )
    if cfg.get("modes"):
        m = m.select([i - 1 for i in cfg["modes"]])
    return m


def objective_from(cfg: dict) -> ObjectiveSpec:
    return ObjectiveSpec(**cfg)


def parameters_from(model, cfg: dict) -> ParameterSet:
    params = model.parameters
    if cfg.get("names"):
        params = params.subset(cfg["names"])
    if cfg.get("bounds"):
        params = params.with_bounds({k: tuple(v) for k, v in cfg["bounds"].items()})
    return params


def build_problem(
    config: dict, structure_options: dict | None = None, measured_cfg: dict | None = None
) -> UpdatingProblem:
    """The updating problem described by a (resolved) config dict."""
    options = {**config["structure"]["options"], **(structure_options or {})}
    model = make_structure(config["structure"]["name"], **options)
    measured = measured_from(measured_cfg or config["measured"])
    return UpdatingProblem(
        model,
        measured,
        parameters_from(model, config["parameters"]),
        objective_from(config["objective"]),
    )


def _evaluation_bar(spec: dict, config: dict):
    """A progress bar over evaluations, for long runs executed in the foreground process."""
    execution = config.get("execution", {})
    if not execution.get("progress_evaluations") or execution.get("backend", "serial") != "serial":
        return None
    from tqdm.auto import tqdm

    return tqdm(total=spec["budget"]["max_evaluations"], desc=f"{spec['label']} seed {spec['seed']}",
                unit="eval", leave=False, position=1)


def _history_rows(base: dict, history: np.ndarray) -> list[dict]:
    if history.size == 0:
        return []
    known = np.where(np.isnan(history), np.inf, history)  # NaN: no successful evaluation yet
    keep = np.flatnonzero(np.r_[True, known[1:] < known[:-1]])
    if keep[-1] != history.size - 1:
        keep = np.r_[keep, history.size - 1]
    return [{**base, "evaluation": int(i + 1), "best_objective": float(history[i])} for i in keep]


def _mode_rows(base: dict, case: str, problem: UpdatingProblem, theta: np.ndarray) -> list[dict]:
    try:
        table = problem.mode_table(theta)
    except ModelEvaluationError as exc:
        return [{**base, "case": case, "mode": 0, "error": str(exc)}]
    table = table.rename(columns={"label": "mode_label"})
    return [{**base, "case": case, **row} for row in table.to_dict("records")]


def evaluation_runner(execution: dict):
    """The runner for a run's model evaluations, from ``execution.evaluation_backend``.

    "processes": a local pool of ``workers`` processes; "dask": the cluster this run executes
    on (inside a Dask worker) or the one at ``scheduler``. Returns (runner, close).
    """
    backend = execution.get("evaluation_backend", "serial")
    if backend == "serial":
        return None, lambda: None
    if backend == "processes":
        from framework.parallel import ProcessRunner

        runner = ProcessRunner(execution.get("workers", 2))
        return runner, runner.close
    from distributed import Client, get_worker

    from framework.parallel import DaskRunner

    try:
        get_worker()
        return DaskRunner(None), lambda: None  # inside a Dask worker: use its cluster
    except ValueError:
        pass
    if not execution.get("scheduler"):
        raise ValueError("execution.evaluation_backend=dask needs execution.scheduler outside a Dask worker")
    client = Client(execution["scheduler"])
    return DaskRunner(client), client.close


def execute_run(spec: dict, runner=None) -> dict[str, list[dict]]:
    """Run one spec and return its rows for every table."""
    config = spec["config"]
    close = lambda: None  # noqa: E731
    if runner is None:
        try:
            runner, close = evaluation_runner(config.get("execution", {}))
        except Exception as exc:
            runner = None
            log.warning("evaluation backend unavailable (%s); evaluating serially", exc)
    try:
        return _execute(spec, config, runner)
    finally:
        close()


def run_key(spec: dict) -> dict:
    """The columns that identify a run in every table."""
    return {
        "run_id": spec["run_id"],
        "study": spec["study"],
        "label": spec["label"],
        "algorithm": spec["algorithm"],
        "variant": spec["variant"],
        "seed": spec["seed"],
        "structure": spec["config"]["structure"]["name"],
    }


def error_tables(spec: dict, exc: BaseException) -> dict[str, list[dict]]:
    """The rows of a run that failed as a whole: one runs row with status 'error'."""
    tables: dict[str, list[dict]] = {t: [] for t in TABLES}
    tables["runs"].append({**run_key(spec), "objective": np.nan, "n_evaluations": 0, "n_iterations": 0,
                           "wall_s": 0.0, "status": "error", "error": f"{type(exc).__name__}: {exc}"})
    return tables


def _execute(spec: dict, config: dict, runner) -> dict[str, list[dict]]:
    base = run_key(spec)
    structure = config["structure"]["name"]
    tables: dict[str, list[dict]] = {t: [] for t in TABLES}
    try:
        problem = build_problem(config)
        bar = _evaluation_bar(spec, config)
        try:
            result = run_optimizer(
                spec["algorithm"], problem, spec["seed"], Budget(**spec["budget"]),
                runner=runner, progress=bar.update if bar is not None else None, **spec["settings"],
            )  # fmt: skip
        finally:
            if bar is not None:
                bar.close()
    except Exception as exc:  # a failed run is data, not the end of the study
        log.warning("run %s failed: %s", spec["run_id"], exc)
        failed = error_tables(spec, exc)
        failed["runs"][0]["traceback"] = traceback.format_exc(limit=5)
        return failed
    tables["runs"].append(
        {
            **base,
            "structure": structure,
            "objective": result.objective,
            "n_evaluations": result.n_evaluations,
            "n_iterations": result.n_iterations,
            "wall_s": result.wall_s,
            "status": result.status,
            "error": "",
            "n_failed_evaluations": result.n_failed,
            "failures": result.failures,
            "message": result.message,
            "condition_number": result.extra.get("condition_number", np.nan),
        }
    )
    params = problem.parameters
    ratios = params.to_ratio(result.theta_best)
    for p, value, ratio, x in zip(params, result.theta_best, ratios, result.x_best):
        tables["parameters"].append(
            {
                **base,
                "parameter": p.name,
                "unit": p.unit,
                "initial": p.initial,
                "lower": p.lower,
                "upper": p.upper,
                "value": float(value),
                "ratio": float(ratio),
                "normalized": float(x),
            }
        )
    tables["history"] = _history_rows(base, result.history)
    tables["extra"] = _extra_rows(base, result.extra)
    if result.status == "failed":  # every evaluation failed: no updated parameters to predict with
        return tables
    tables["modes"] += _mode_rows(base, "base", problem, result.theta_best)
    theta = params.as_dict(result.theta_best)
    for case in config.get("validation", []):
        try:
            vproblem = build_problem(
                config, structure_options=case["structure_options"], measured_cfg=case["measured"]
            )
            tables["modes"] += _mode_rows(base, case["case"], vproblem, vproblem.parameters.from_dict(theta))
        except Exception as exc:
            tables["modes"].append(
                {**base, "case": case["case"], "mode": 0, "error": f"{type(exc).__name__}: {exc}"}
            )
    return tables


def _extra_rows(base: dict, extra: dict[str, Any]) -> list[dict]:
    """Algorithm-specific facts, one row per key (lists JSON-encoded), e.g. SNT minima."""
    import json

    rows = []
    for key, value in extra.items():
        rows.append({**base, "key": key, "value": json.dumps(value, default=float)})
    return rows
