"""Run kind ``updating``: one optimizer run on one model-updating problem.

A study lists algorithms (each an optimizer with settings, runs and budget overrides); each
run updates the structure's parameters to the measured modes and predicts the validation
cases with the updated values. Tables:

- ``runs``: one row per run: structure, algorithm, objective (best Pi), n_evaluations
  (model evaluations + eigen-solve equivalents of exact Jacobians), n_jacobians,
  n_iterations, wall_s, status (the optimizer's stop reason: target, stalled, converged, budget,
  max_iterations, completed; or failed, error: :class:`framework.core.status.Status`), error,
  n_failed_evaluations, failures, message, condition_number (SM), every optimizer setting as
  its own column, and the result columns an adapter reports as ``extra["run_columns"]``
  (hybrid: global_objective, global_evaluations, local_evaluations, ...; multistart:
  n_starts_run, n_stopped_early, best_start);
- ``parameters``: run x parameter: unit, initial, lower, upper, value, ratio, normalized
  (no rows for a failed run: a failed point is not an updated value);
- ``modes``: run x case x measured mode: f_measured_hz, f_model_hz, error_pct, mac, matched;
- ``history``: best objective so far at every evaluation where it improved, and the last;
- ``extra``: optimizer-specific facts as JSON text (SNT minima, singular values, ...);
- ``identifiability``: run x singular direction of the whitened Jacobian at the optimum.

The linearized uncertainty at the optimum (:mod:`framework.inference.tables`, one Jacobian
per run, never fatal) adds ``chi2``, ``n_data``, ``log_evidence_laplace``, ``uq_jacobian``,
``uq_error``, ``noise_frequency_source``, ``noise_shape_source`` (where the data's standard
deviations came from: data / estimated / assumed, :mod:`framework.inference.noise`) to ``runs``
and ``std``, ``ci90_lower``, ``ci90_upper`` (physical units), ``noise_assumed`` to
``parameters``.
"""

from __future__ import annotations

import hashlib
import json
import logging
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import (
    AfterValidator,
    ConfigDict,
    Field,
    SerializeAsAny,
    StrictInt,
    ValidationError,
    field_serializer,
    field_validator,
    model_validator,
)

from framework.core.errors import InputError, ModelEvaluationError
from framework.core.parameters import ParameterSet
from framework.core.status import Status
from framework.measured.load import load_measured
from framework.measured.modes import MeasuredModes
from framework.optimizers import OPTIMIZERS, Budget, Settings, run_optimizer
from framework.structures.registry import builtin_measured, check_reference, is_reference, make_structure
from framework.study.kinds.base import ANALYSES, Kind, task_key
from framework.study.schema import Strict, StudyHeader
from framework.study.shapes import shape_states
from framework.updating.objectives import ObjectiveSpec
from framework.updating.problem import UpdatingProblem

log = logging.getLogger(__name__)

TABLES = ("runs", "parameters", "modes", "history", "extra", "identifiability")

#: largest magnitude accepted for a bound or initial value (keeps spans finite)
MAX_MAGNITUDE = 1e100


# ---- schema ------------------------------------------------------------------------------
class StructureConfig(Strict):
    name: str = Field(min_length=1)
    options: dict[str, Any] = Field(default_factory=dict)


class MeasuredConfig(Strict):
    """Either a built-in data set (``builtin`` + ``case``) or a file (YAML/CSV)."""

    builtin: str | None = None
    case: str = "base"
    #: keywords for a built-in data set's provider (e.g. the lab frame's ``congruence``)
    options: dict[str, Any] = Field(default_factory=dict)
    file: str | None = None
    #: for a UFF file (.unv/.uff): the mapping file from test node + direction to model DOF
    mapping: str | None = None
    #: 1-based subset of the measured modes to use
    modes: list[StrictInt] | None = None

    @model_validator(mode="after")
    def _one_source(self):
        if (self.builtin is None) == (self.file is None):
            raise ValueError("give exactly one of 'builtin' or 'file'")
        if self.mapping is not None and self.file is None:
            raise ValueError("'mapping' goes with a UFF 'file'")
        if self.modes is not None:
            if not self.modes:
                raise ValueError("modes: give at least one mode number, or leave it out for all")
            bad = [m for m in self.modes if m < 1]
            if bad:
                raise ValueError(f"modes are numbered from 1, got {bad}")
            if len(set(self.modes)) != len(self.modes):
                raise ValueError(f"modes are repeated: {self.modes}")
        return self


class ValidationCase(Strict):
    case: str = Field(min_length=1)
    structure_options: dict[str, Any] = Field(default_factory=dict)
    measured: MeasuredConfig


def _check_bounds(b: list[float]) -> list[float]:
    if len(b) != 2:
        raise ValueError(f"bounds must be [lower, upper], got {b}")
    lo, hi = b
    if not all(np.isfinite(b)) or max(abs(lo), abs(hi)) > MAX_MAGNITUDE:
        raise ValueError(f"bounds must be finite numbers of magnitude <= 1e100, got [{lo}, {hi}]")
    if lo > hi:
        raise ValueError(f"bounds are swapped: [{lo}, {hi}]")
    if lo == hi:
        raise ValueError(f"bounds are empty: [{lo}, {hi}]")
    return b


Bounds = Annotated[list[float], AfterValidator(_check_bounds)]


class ParametersConfig(Strict):
    names: list[str] | None = None
    bounds: dict[str, Bounds] = Field(default_factory=dict)


class BudgetConfig(Budget):
    """The optimizers' budget and termination rule, read with strict types."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=True, allow_inf_nan=False)


class AlgorithmConfig(Strict):
    algorithm: str
    #: the optimizer's settings: validated once, when the config is read, into the optimizer's
    #: Settings object (:meth:`framework.optimizers.base.Optimizer.validate`), which the run
    #: hands to the optimizer as it is; written back (config.yaml, variants) as given
    settings: SerializeAsAny[Settings] = Field(default_factory=Settings)
    runs: StrictInt | None = Field(None, ge=1, le=100_000)
    budget: dict[str, Any] = Field(default_factory=dict)
    #: "pointwise": a population is evaluated one point per call (as the source's toolboxes;
    #: for timing), "batch": in one vectorized call where the model allows it (default)
    evaluation: Literal["batch", "pointwise"] = "batch"

    @model_validator(mode="before")
    @classmethod
    def _typed_settings(cls, data):
        if not isinstance(data, dict) or not isinstance(data.get("algorithm"), str):
            return data
        name = data["algorithm"]
        if name not in OPTIMIZERS:
            raise ValueError(f"unknown algorithm {name!r}; known: {sorted(OPTIMIZERS)}")
        try:
            settings = OPTIMIZERS[name].validate(data.get("settings", {}))
        except ValueError as exc:
            raise ValueError(f"{exc} for algorithm {name!r}") from None
        return {**data, "settings": settings}

    @field_serializer("settings")
    def _as_given(self, settings: Settings) -> dict:
        return settings.model_dump(mode="json", exclude_unset=True)

    @model_validator(mode="after")
    def _budget_valid(self):
        try:
            Budget.model_validate(self.budget, strict=True)
        except ValidationError as exc:
            first = exc.errors()[0]
            raise ValueError(f"budget.{'.'.join(map(str, first['loc']))}: {first['msg']}") from None
        return self


class Config(StudyHeader):
    kind: Literal["updating"] = "updating"
    structure: StructureConfig
    measured: MeasuredConfig
    validation: list[ValidationCase] = Field(default_factory=list)
    parameters: ParametersConfig = Field(default_factory=ParametersConfig)
    objective: ObjectiveSpec = Field(default_factory=ObjectiveSpec)
    budget: BudgetConfig = Field(default_factory=BudgetConfig)
    algorithms: dict[str, AlgorithmConfig]

    @model_validator(mode="before")
    @classmethod
    def _legacy_options(cls, data):
        """``options:`` (analysis options of earlier configs) is read as ``report:``."""
        if isinstance(data, dict) and "options" in data:
            data = dict(data)
            options = data.pop("options")
            if isinstance(options, dict):
                data["report"] = {**options, **(data.get("report") or {})}
            else:
                data["options"] = options  # let the schema name the bad value
        return data

    @field_validator("algorithms")
    @classmethod
    def _non_empty(cls, v):
        if not v:
            raise ValueError("at least one algorithm is required")
        return v


def check(cfg: Config, source: str, base_dir: Path | None = None) -> None:
    """Resolve data-file paths (relative to the config's folder if not found as given)."""
    files = [("measured.file", cfg.measured)] + [
        (f"validation[{i}].measured.file", v.measured) for i, v in enumerate(cfg.validation)
    ]
    for field_name, measured in files:
        for attr in ("file", "mapping"):
            given = getattr(measured, attr)
            if given is None:
                continue
            where = field_name.removesuffix(".file") + f".{attr}"
            path = Path(given)
            if not path.is_absolute() and not path.exists() and base_dir is not None and (base_dir / path).exists():
                path = base_dir / path
            if not path.exists():
                raise InputError(f"{source}: {where}: file not found: {given}")
            if path.is_dir():
                raise InputError(f"{source}: {where}: is a folder, not a data file: {given}")
            setattr(measured, attr, str(path))


# ---- plan --------------------------------------------------------------------------------
def plan_runs(cfg: Config, sweep_values: dict[str, Any]) -> list[dict]:
    """One run per algorithm entry and seed; the task holds everything the run needs."""
    data = cfg.model_dump(mode="json")
    common = {k: data[k] for k in ("structure", "measured", "validation", "parameters", "objective")}
    common["objective"] = effective_objective(common["objective"])
    # empty measured options are left out, so runs stored before the field existed keep their ids
    _drop_empty_options(common["measured"])
    for case in common["validation"] or []:
        _drop_empty_options(case.get("measured"))
    parts = []
    for label, alg in cfg.algorithms.items():
        budget = Budget.model_validate({**data["budget"], **alg.budget}).model_dump(mode="json")
        relevant = [k for k in sweep_values if not k.startswith("algorithms.") or k.startswith(f"algorithms.{label}.")]
        task = {**common, "algorithm": alg.algorithm, "settings": alg.settings, "budget": budget}
        if alg.evaluation != "batch":  # only when set: the ids of earlier runs stay
            task["evaluation"] = alg.evaluation
        columns = {"structure": cfg.structure.name, "algorithm": alg.algorithm}
        for i in range(alg.runs or cfg.runs):
            parts.append({"label": label, "seed": cfg.seed + i, "task": task, "columns": columns,
                          "relevant": relevant})
    return parts


def effective_objective(objective: dict) -> dict:
    """The objective section as it acts: a formulation that reads no options (``spec``) gets none,
    so that a study sweeping the formulation and another formulation's options (e.g.
    ``objective.options.shape_term``) plans each of its runs once (equal tasks, one run id)."""
    from framework.updating.formulations import get_formulation

    if objective.get("options") and get_formulation(objective["formulation"]).check_options is None:
        return {**objective, "options": {}}
    return objective


def identity(task: dict) -> dict:
    """What determines a run's result, as plain data: the task, its optimizer settings as JSON
    data (as validated, defaults filled in), each data file replaced by a hash of its content
    (so moving a file or the project keeps the id)."""
    ident = dict(task)
    if isinstance(task.get("settings"), Settings):
        ident["settings"] = task["settings"].model_dump(mode="json")
    ident["measured"] = _measured_identity(task["measured"])
    ident["validation"] = [{**c, "measured": _measured_identity(c["measured"])} for c in task["validation"]]
    return ident


def _measured_identity(measured: dict) -> dict:
    out = dict(measured)
    for attr in ("file", "mapping"):
        if out.get(attr):
            try:
                out[f"{attr}_sha256"] = hashlib.sha256(Path(out[attr]).read_bytes()).hexdigest()
            except OSError:
                out[f"{attr}_sha256"] = f"unreadable:{out[attr]}"
        out.pop(attr, None)
    return out


# ---- problem -----------------------------------------------------------------------------
def measured_from(cfg: dict) -> MeasuredModes:
    """Measured modes of a ``measured`` section: a built-in data set or a file (YAML, CSV, or
    UFF with a mapping file), optionally a 1-based subset of its modes."""
    if cfg.get("file"):
        m = load_measured(cfg["file"], cfg.get("mapping"))
    else:
        m = builtin_measured(cfg["builtin"], cfg.get("case", "base"), **(cfg.get("options") or {}))
    if cfg.get("modes"):
        m = m.select_modes(cfg["modes"], where=f"{m.source}: measured.modes")
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


def build_problem(task: dict, structure_options: dict | None = None, measured_cfg: dict | None = None
                  ) -> UpdatingProblem:
    """The updating problem of a task (or of one of its validation cases)."""
    options = {**task["structure"]["options"], **(structure_options or {})}
    model = make_structure(task["structure"]["name"], **options)
    measured = measured_from(measured_cfg or task["measured"])
    return UpdatingProblem(model, measured, parameters_from(model, task["parameters"]),
                           objective_from(task["objective"]))


#: the task sections that make a run's problem (runs sharing them share one preflight)
PROBLEM_KEYS = ("structure", "measured", "validation", "parameters", "objective")


def problem_key(spec: dict) -> str:
    return task_key(spec, PROBLEM_KEYS)


def preflight(spec: dict, build_references: bool = True) -> None:
    """Build the run's problems (model, data, parameters, objective; each validation case)
    before any run starts, so bad input fails early with an InputError naming the field and value.

    With ``build_references=False`` (``gomu validate`` without ``--build``) code named in the
    config as ``module:function`` is not imported: only data files are read."""
    task = spec["task"]
    cases = [(None, task["measured"])] + [(c["structure_options"], c["measured"]) for c in task["validation"]]
    if build_references or not _names_code(task):
        for options, measured in cases:
            build_problem(task, structure_options=options, measured_cfg=measured)
    else:  # the checks that import nothing
        check_named_code(task)
        for _, measured in cases:
            if not is_reference(measured.get("builtin") or ""):
                measured_from(measured)


def check_named_code(task: dict) -> None:
    """The checks of code named in a task that import nothing (``module:function`` form, not
    the standard library; :func:`framework.structures.registry.check_reference`)."""
    name = task["structure"]["name"]
    if is_reference(name):
        check_reference(name, f"structure.name={name!r}")
    for measured in [task["measured"]] + [c["measured"] for c in task["validation"]]:
        builtin = measured.get("builtin") or ""
        if is_reference(builtin):
            check_reference(builtin, f"measured.builtin={builtin!r}")


def _names_code(task: dict) -> bool:
    """Does the task name user code (``module:function``) as structure or data provider?"""
    names = [task["structure"]["name"], task["measured"].get("builtin") or ""]
    names += [c["measured"].get("builtin") or "" for c in task["validation"]]
    return any(is_reference(n) for n in names)


def user_model(task: dict) -> bool:
    """Is the task's model user code (``module:function`` outside ``framework``)? Its
    evaluations are then isolated by default (``execution.isolate: auto``)."""
    name = task["structure"]["name"]
    return is_reference(name) and not name.startswith("framework.")


# ---- one run -----------------------------------------------------------------------------
def _evaluation_bar(spec: dict):
    """A progress bar over evaluations, for long runs executed in the foreground process."""
    execution = spec.get("execution", {})
    if not execution.get("progress_evaluations") or execution.get("backend", "serial") != "serial":
        return None
    from tqdm.auto import tqdm

    return tqdm(total=spec["task"]["budget"]["max_evaluations"], desc=f"{spec['label']} seed {spec['seed']}",
                unit="eval", leave=False, position=1)


def _drop_empty_options(measured: dict | None) -> None:
    if isinstance(measured, dict) and not measured.get("options"):
        measured.pop("options", None)


def run(spec: dict, runner) -> dict[str, list[dict]]:
    """One optimizer run and the rows of every table; ``runner`` evaluates the model
    (:func:`framework.study.kinds.base.evaluation_runner`)."""
    task = spec["task"]
    tables: dict[str, list[dict]] = {t: [] for t in TABLES}
    problem = build_problem(task)
    bar = _evaluation_bar(spec)
    try:
        result = run_optimizer(task["algorithm"], problem, spec["seed"], Budget(**task["budget"]),
                               settings=task["settings"], runner=runner,
                               progress=bar.update if bar is not None else None,
                               pointwise=task.get("evaluation") == "pointwise")
    finally:
        if bar is not None:
            bar.close()
    failed = result.status == Status.FAILED
    tables["runs"].append({
        "objective": result.objective,
        "n_evaluations": result.n_evaluations,
        "n_jacobians": result.n_jacobians,
        "n_iterations": result.n_iterations,
        "wall_s": result.wall_s,
        "status": result.status,
        "error": "",
        "n_failed_evaluations": result.n_failed,
        "failures": result.failures,
        "message": result.message,
        "condition_number": result.extra.get("condition_number", np.nan),
        **setting_columns(task["settings"].model_dump(mode="json")),
        **result.extra.get("run_columns", {}),  # an adapter's own result columns (hybrid phases)
    })
    tables["history"] = history_rows(result.history)
    tables["extra"] = extra_rows({k: v for k, v in result.extra.items() if k != "run_columns"})
    if failed:
        return tables
    from framework.inference.tables import linearized_columns

    uq = linearized_columns(problem, result.x_best, runner=runner)
    tables["runs"][0].update(uq["run"])
    tables["identifiability"] = uq["identifiability"]
    params = problem.parameters
    ratios = params.to_ratio(result.theta_best)
    for p, value, ratio, x, extra in zip(params, result.theta_best, ratios, result.x_best, uq["parameters"]):
        tables["parameters"].append({"parameter": p.name, "unit": p.unit, "initial": p.initial, "lower": p.lower,
                                     "upper": p.upper, "value": float(value), "ratio": float(ratio),
                                     "normalized": float(x), **extra})
    tables["modes"] += mode_rows("base", problem, result.theta_best, runner)
    theta = params.as_dict(result.theta_best)
    for case in task.get("validation", []):
        try:
            vproblem = build_problem(task, structure_options=case["structure_options"], measured_cfg=case["measured"])
            tables["modes"] += mode_rows(case["case"], vproblem, vproblem.parameters.from_dict(theta), runner)
        except Exception as exc:  # a failed prediction is a row, not the end of the run
            tables["modes"].append({"case": case["case"], "mode": 0, "error": f"{type(exc).__name__}: {exc}"})
    return tables


def setting_columns(settings: dict, prefix: str = "") -> dict[str, Any]:
    """Every optimizer setting as a column; nested settings (SNT's ``pso``) flattened with ``_``,
    lists as JSON text."""
    out: dict[str, Any] = {}
    for key, value in settings.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            out.update(setting_columns(value, f"{name}_"))
        elif isinstance(value, list):
            out[name] = json.dumps(value)
        else:
            out[name] = value
    return out


def history_rows(history: np.ndarray) -> list[dict]:
    history = np.asarray(history, float)
    if history.size == 0:
        return []
    known = np.where(np.isnan(history), np.inf, history)  # NaN: no successful evaluation yet
    keep = np.flatnonzero(np.r_[True, known[1:] < known[:-1]])
    if keep[-1] != history.size - 1:
        keep = np.r_[keep, history.size - 1]
    return [{"evaluation": int(i + 1), "best_objective": float(history[i])} for i in keep]


def mode_rows(case: str, problem: UpdatingProblem, theta: np.ndarray, runner=None) -> list[dict]:
    try:
        table = problem.mode_table(theta, runner=runner)
    except ModelEvaluationError as exc:
        return [{"case": case, "mode": 0, "error": str(exc)}]
    table = table.rename(columns={"label": "mode_label"})
    return [{"case": case, **row} for row in table.to_dict("records")]


def extra_rows(extra: dict[str, Any]) -> list[dict]:
    """Optimizer-specific facts, one row per key, the value as JSON text."""
    from framework.study.store import _json_default

    return [{"key": key, "value": json.dumps(value, default=_json_default)} for key, value in extra.items()]


# ---- analyses and figures ----------------------------------------------------------------
def analyses(tables: dict, report: dict) -> dict:
    """Derived tables named in ``report`` (e.g. ``selection``), from the tables only."""
    from framework.report.analyses import run_analyses
    from framework.study.structure_hooks import with_structure_choices

    return run_analyses(tables, with_structure_choices(report))


def figures(tables: dict, out_dir: Path, report: dict) -> list[Path]:
    from framework.report.analyses import analysis_figures
    from framework.report.figures.updating import updating_figures

    return updating_figures(tables, out_dir) + analysis_figures(tables, out_dir, report)


def shapes(cfg: Config, tables: dict, specs: list[dict]) -> list[tuple]:
    """Mode shapes at the initial point and at the best run's parameters, per structure."""
    return shape_states(tables, specs, build_problem, best_run=True)


KIND = Kind(
    name="updating", config=Config, tables=TABLES, plan_runs=plan_runs, run=run, check=check, identity=identity,
    preflight=preflight, preflight_key=problem_key, evaluates_model=True, user_code=user_model, report=ANALYSES,
    analyses=analyses, figures=figures, shapes=shapes,
)
