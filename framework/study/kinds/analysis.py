"""Run kind ``analysis``: evaluate a model at given points, without optimizing.

A study names a structure, measured data (and validation cases), parameters, an objective
and ``points``, e.g. the initial model and an updated one::

    points:
      initial: {}
      updated: {values: {k_r2: 723.07, k_r3: 1912.6}}    # or ratios: {K_cable: 0.76}
    pairings: [objective, type]
    sensitivity: {rel_step: 1.0e-3, widen: [0.01, 2.0]}

One run per point (its ``label`` is the point's name, per variant of the study). Tables:

- ``points``: one row per run: objective Pi at the point, status ("ok", "failed" when the
  model fails there), error, n_evaluations (model evaluations of the run), wall_s,
  condition_number (with ``sensitivity``);
- ``parameters``: point x parameter: unit, initial, lower, upper, value, ratio;
- ``modes``: point x case x pairing x measured mode: f_measured_hz, f_model_hz, error_pct,
  mac, matched, plus the model's per-mode facts of the paired mode where the model gives
  them (e.g. the bridge's mode_type, deck_energy, cable_energy) and the data's per-mode
  facts (e.g. design_model_hz; the measured mode types as ``measured_type``). Pairing
  "objective" pairs as the objective does; "type" pairs each measured mode with the
  nearest-frequency model mode of the same type (needs mode types in both);
- ``sensitivity``: point x parameter x mode: relative sensitivities
  S_f = (df/f)/(dp/p) and S_MAC = dMAC/(dp/p) by :func:`framework.updating.sensitivity.sensitivity_matrix`
  (forward differences of relative step ``rel_step``); ``widen: [lo, hi]`` evaluates the
  differences with bounds [lo, hi] x initial, so no step is clipped or turned backwards at
  a bound;
- ``identifiability``: point x singular value of S = [S_f; S_MAC]: singular_value,
  condition_number s_max / s_min;
- ``parameter_correlation``: point x parameter pair: the correlation
  rho_jk = C_jk / sqrt(C_jj C_kk), C = (S^T S)^+, of a linearized least-squares fit.

Every structure option that is a scalar is also a column (e.g. cable_elements). A point
lying outside the parameters' bounds is an input error (the problem would clip it). Nothing
here is random: the header's ``runs`` is not used and ``seed`` only names the runs.
"""

from __future__ import annotations

import logging
import time
from pathlib import Path
from typing import Literal

import numpy as np
from pydantic import Field, field_validator, model_validator

from framework.core.errors import InputError, ModelEvaluationError
from framework.core.status import Status
from framework.study.kinds.base import ANALYSES, Kind, failure
from framework.study.kinds.updating import (
    MeasuredConfig,
    ParametersConfig,
    StructureConfig,
    ValidationCase,
    _names_code,
    build_problem,
    check_named_code,
    user_model,
)
from framework.study.kinds.updating import check as _check_files
from framework.study.kinds.updating import identity as _identity
from framework.study.schema import Strict, StudyHeader
from framework.study.shapes import shape_states
from framework.updating.objectives import ObjectiveSpec

log = logging.getLogger(__name__)

TABLES = ("points", "parameters", "modes", "sensitivity", "identifiability", "parameter_correlation")

PAIRINGS = ("objective", "type")


# ---- schema ------------------------------------------------------------------------------
class PointConfig(Strict):
    """A point: the initial values, with some replaced by physical values or by ratios to
    the initial values (a parameter may be named in only one of the two)."""

    values: dict[str, float] = Field(default_factory=dict)
    ratios: dict[str, float] = Field(default_factory=dict)

    @model_validator(mode="after")
    def _disjoint(self):
        both = sorted(set(self.values) & set(self.ratios))
        if both:
            raise ValueError(f"parameter(s) {both} given both as values and as ratios")
        bad = [k for k, v in {**self.values, **self.ratios}.items() if not np.isfinite(v)]
        if bad:
            raise ValueError(f"values of {bad} must be finite numbers")
        return self


class SensitivityConfig(Strict):
    rel_step: float = Field(1e-3, gt=0, lt=0.5)
    include_mac: bool = True
    #: evaluate the differences with bounds [lo, hi] x initial value (0 <= lo < 1 < hi)
    widen: list[float] | None = None

    @field_validator("widen")
    @classmethod
    def _widen(cls, v):
        if v is not None and (len(v) != 2 or not 0 <= v[0] < 1 < v[1] or not np.isfinite(v[1])):
            raise ValueError(f"widen must be [lo, hi] with 0 <= lo < 1 < hi, got {v}")
        return v


class Config(StudyHeader):
    kind: Literal["analysis"]
    structure: StructureConfig
    measured: MeasuredConfig
    validation: list[ValidationCase] = Field(default_factory=list)
    parameters: ParametersConfig = Field(default_factory=ParametersConfig)
    objective: ObjectiveSpec = Field(default_factory=ObjectiveSpec)
    points: dict[str, PointConfig] = Field(default_factory=lambda: {"initial": PointConfig()})
    pairings: list[Literal["objective", "type"]] = Field(default_factory=lambda: ["objective"])
    sensitivity: SensitivityConfig | None = None

    @field_validator("points")
    @classmethod
    def _points(cls, v):
        from framework.study.schema import NAME_PATTERN

        if not v:
            raise ValueError("give at least one point (e.g. initial: {})")
        bad = [name for name in v if not NAME_PATTERN.match(name)]
        if bad:
            raise ValueError(f"point names must be letters, digits and _ . + -, got {bad}")
        return v

    @field_validator("pairings")
    @classmethod
    def _pairings(cls, v):
        if not v or len(set(v)) != len(v):
            raise ValueError(f"give each pairing at most once and at least one, got {v}")
        return v



def check(cfg: Config, source: str, base_dir: Path | None = None) -> None:
    """Data files as for ``updating`` (found relative to the config's folder)."""
    _check_files(cfg, source, base_dir)


# ---- plan --------------------------------------------------------------------------------
def plan_runs(cfg: Config, sweep_values: dict) -> list[dict]:
    """One run per point; the task holds the model, data, the point and what to compute."""
    data = cfg.model_dump(mode="json")
    common = {k: data[k] for k in ("structure", "measured", "validation", "parameters", "objective",
                                   "pairings", "sensitivity")}
    columns = {"structure": cfg.structure.name}
    columns.update({k: v for k, v in cfg.structure.options.items()
                    if v is None or isinstance(v, bool | int | float | str)})
    return [{"label": name, "seed": cfg.seed, "task": {**common, "point": data["points"][name]},
             "columns": columns} for name in cfg.points]


def identity(task: dict) -> dict:
    """The task, each data file replaced by a hash of its content."""
    return _identity(task)


def preflight(spec: dict, build_references: bool = True) -> None:
    """Build the run's problem and point before any run starts; with ``build_references=False``
    a task that names code (``module:function``) is not built."""
    task = spec["task"]
    if not build_references and _names_code(task):
        check_named_code(task)  # imports nothing
        return
    problem = build_problem(task)
    point_theta(problem.parameters, task["point"], spec["label"])
    if "type" in task["pairings"] and "mode_types" not in (problem.measured.meta or {}):
        raise InputError(f"pairings: 'type' needs the measured mode types (meta.mode_types) in "
                         f"{problem.measured.source}")
    for case in task["validation"]:
        build_problem(task, structure_options=case["structure_options"], measured_cfg=case["measured"])


def point_theta(params, point: dict, name: str = "") -> np.ndarray:
    """Physical parameter vector of a point; InputError for an unknown name or a value
    outside the bounds (the evaluation would silently clip it)."""
    theta = params.initial.astype(float).copy()
    unknown = sorted((set(point.get("values", {})) | set(point.get("ratios", {}))) - set(params.names))
    if unknown:
        raise InputError(f"points.{name}: {unknown} are not parameters of the study; known: {params.names}")
    for k, value in point.get("values", {}).items():
        theta[params.names.index(k)] = value
    for k, ratio in point.get("ratios", {}).items():
        theta[params.names.index(k)] = ratio * params.initial[params.names.index(k)]
    outside = [f"{p.name}={t:.6g} not in [{p.lower:.6g}, {p.upper:.6g}]" for p, t in zip(params, theta)
               if not p.lower - 1e-12 * p.span <= t <= p.upper + 1e-12 * p.span]
    if outside:
        raise InputError(f"points.{name}: outside the bounds: {'; '.join(outside)}")
    return np.clip(theta, params.lower, params.upper)


# ---- one run -----------------------------------------------------------------------------
def run(spec: dict, runner) -> dict[str, list[dict]]:
    """Evaluate one point: objective, parameters, modes of every case, sensitivities; the model
    is evaluated by ``runner`` (isolated for user code, as in an updating run)."""
    t0 = time.perf_counter()
    task = spec["task"]
    tables: dict[str, list[dict]] = {t: [] for t in TABLES}
    problem = build_problem(task)
    theta = point_theta(problem.parameters, task["point"], spec["label"])
    params = problem.parameters
    for p, value, ratio in zip(params, theta, params.to_ratio(theta)):
        tables["parameters"].append({"parameter": p.name, "unit": p.unit, "initial": p.initial, "lower": p.lower,
                                     "upper": p.upper, "value": float(value), "ratio": float(ratio)})
    ev = problem.evaluate(params.to_normalized(theta)[None, :], runner)
    row = {"objective": float(ev.objective[0]), "status": Status.OK, "error": "", "n_evaluations": 1,
           "wall_s": 0.0, "condition_number": np.nan}
    if not ev.ok[0]:
        row.update(failure(str(ev.reasons[0])))
    cases = [("base", problem)] + [
        (c["case"], build_problem(task, structure_options=c["structure_options"], measured_cfg=c["measured"]))
        for c in task["validation"]]
    for case, case_problem in cases:
        rows, n = mode_rows(case_problem, case_problem.parameters.from_dict(params.as_dict(theta)), task["pairings"],
                            runner)
        tables["modes"] += [{"case": case, **r} for r in rows]
        row["n_evaluations"] += n
    if task.get("sensitivity") and ev.ok[0]:
        try:
            result = sensitivity(problem, theta, task["sensitivity"], runner)
        except ModelEvaluationError as exc:  # a failed step is a row, not the end of the run
            row.update(failure(f"sensitivity: {exc}"))
        else:
            row["condition_number"] = result.condition_number
            row["n_evaluations"] += len(params) + 1
            f0 = np.asarray(ev.correlations[0].f_model_hz, float)
            for name, rows in sensitivity_rows(result, theta, f0, task["sensitivity"]["rel_step"]).items():
                tables[name] += rows
    row["wall_s"] = time.perf_counter() - t0
    tables["points"].append(row)
    return tables


def sensitivity(problem, theta: np.ndarray, options: dict, runner=None):
    """:func:`framework.updating.sensitivity.sensitivity_matrix` at theta (bounds widened to
    [lo, hi] x initial when ``widen`` is given, so no step is clipped)."""
    from framework.updating.sensitivity import sensitivity_matrix

    widen = tuple(options["widen"]) if options.get("widen") else None
    return sensitivity_matrix(problem, theta0=theta, rel_step=options["rel_step"],
                              include_mac=options["include_mac"], widen=widen, runner=runner)


def sensitivity_rows(result, theta: np.ndarray, f0: np.ndarray, rel_step: float) -> dict[str, list[dict]]:
    """Rows of the sensitivity, identifiability and parameter_correlation tables."""
    out: dict[str, list[dict]] = {"sensitivity": [], "identifiability": [], "parameter_correlation": []}
    for j, name in enumerate(result.parameters):
        for i, label in enumerate(result.modes):
            out["sensitivity"].append({"parameter": name, "value": float(theta[j]), "mode": i + 1, "mode_label": label,
                                       "f_model_hz": float(f0[i]),
                                       "rel_sensitivity_frequency": float(result.frequency[i, j]),
                                       "rel_sensitivity_mac": float(result.mac[i, j]), "rel_step": rel_step})
        for k, other in enumerate(result.parameters):
            out["parameter_correlation"].append({"parameter": name, "parameter_other": other,
                                                 "correlation": float(result.correlation[j, k])})
    for i, s in enumerate(result.singular_values):
        out["identifiability"].append({"index": i + 1, "singular_value": float(s),
                                       "condition_number": float(result.condition_number)})
    return out


def mode_rows(problem, theta: np.ndarray, pairings: list[str], runner=None) -> tuple[list[dict], int]:
    """Mode rows of one case at theta for each pairing, and the model evaluations spent."""
    from framework.updating.pairing import correlation_table

    measured = problem.measured
    result = _modal(problem.model, problem.parameters.as_dict(theta), runner)
    if isinstance(result, Exception):
        return [{"pairing": p, "mode": 0, "error": str(result)} for p in pairings], 1
    rows, n = [], 1
    data_columns = _data_columns(measured)
    for pairing in pairings:
        if pairing == "objective":
            try:
                corr = problem.correlation_at(theta, runner)
            except ModelEvaluationError as exc:
                rows.append({"pairing": pairing, "mode": 0, "error": str(exc)})
                continue
            finally:
                n += 1
            table = correlation_table(corr, measured).rename(columns={"label": "mode_label"})
            index = np.asarray(corr.analytical_index)
        else:
            table, index = type_pairing(result, measured)
        for j, r in enumerate(table.to_dict("records")):
            rows.append({"pairing": pairing, **r, **_model_columns(result, index[j]),
                         **{k: v[j] for k, v in data_columns.items()}})
    return rows, n


def _modal(model, theta: dict, runner=None):
    """The model's modes at theta (or its ModelEvaluationError): in process (``model.modal``)
    when the runner is the in-process one, else through the runner (isolated worker)."""
    from framework.models.base import modal_many, safe_modal

    if runner is None or runner is modal_many:
        return safe_modal(model, theta)
    return runner(model, [theta])[0]


def type_pairing(result, measured):
    """Pair each measured mode with the nearest-frequency model mode of the same type
    (one-to-one within a type), as the bridge data are published: measured mode types in
    ``measured.meta['mode_types']``, model mode types in ``result.mode_info['mode_type']``.
    Returns (mode table, model index per measured mode, -1 when none)."""
    import pandas as pd

    from framework.core.correlation import mac_paired, pair_modes

    types = measured.meta.get("mode_types")
    model_types = result.mode_info.get("mode_type")
    if types is None or model_types is None:
        raise InputError(f"pairings: 'type' needs mode types in the measured data ({measured.source}: "
                         f"{'yes' if types is not None else 'no'}) and in the model's modes "
                         f"({'yes' if model_types is not None else 'no'})")
    f_e = np.asarray(measured.frequencies_hz, float)
    index = -np.ones(f_e.size, dtype=int)
    for kind in dict.fromkeys(types):
        rows = [j for j, t in enumerate(types) if t == kind]
        cands = np.flatnonzero(np.asarray(model_types) == kind)
        if cands.size:
            paired = pair_modes(result.frequencies_hz[cands], f_e[rows], method="frequency").analytical_index
            index[rows] = np.where(paired >= 0, cands[np.maximum(paired, 0)], -1)
    ok = index >= 0
    f_a = np.where(ok, result.frequencies_hz[np.maximum(index, 0)], np.nan)
    mac = np.full(f_e.size, np.nan)
    if measured.has_shapes and ok.any():
        mac[ok] = mac_paired(result.at(measured.dofs)[:, index[ok]], measured.shapes[:, ok])
    table = pd.DataFrame({"mode": np.arange(1, f_e.size + 1), "mode_label": list(measured.labels),
                          "f_measured_hz": f_e, "f_model_hz": f_a, "error_pct": 100.0 * (f_a / f_e - 1.0),
                          "mac": mac, "matched": ok})
    return table, index


def _model_columns(result, index: int) -> dict:
    """The model's per-mode facts (``mode_info``) of model mode ``index`` (None when unpaired)."""
    out = {}
    for key, values in result.mode_info.items():
        value = np.asarray(values)[index] if index >= 0 else None
        out[key] = value.item() if isinstance(value, np.generic) else value
    return out


def _data_columns(measured) -> dict[str, list]:
    """Per-mode facts of the data set (lists of one scalar per mode in ``meta``)."""
    out = {}
    for key, values in (measured.meta or {}).items():
        if isinstance(values, list | tuple) and len(values) == measured.n_modes and all(
                isinstance(v, int | float | str) for v in values):
            out["measured_type" if key == "mode_types" else key] = list(values)
    return out


# ---- analyses and figures ----------------------------------------------------------------
def analyses(tables: dict, report: dict) -> dict:
    from framework.report.analyses import run_analyses
    from framework.study.structure_hooks import with_structure_choices

    return run_analyses(tables, with_structure_choices(report))


def figures(tables: dict, out_dir: Path, report: dict) -> list[Path]:
    from framework.report.analyses import analysis_figures

    return analysis_figures(tables, out_dir, report)


def shapes(cfg: Config, tables: dict, specs: list[dict]) -> list[tuple]:
    """Mode shapes at every point of the variant with the most points, per structure."""
    return shape_states(tables, specs, build_problem, best_run=False)


KIND = Kind(
    name="analysis", config=Config, tables=TABLES, plan_runs=plan_runs, run=run, check=check, identity=identity,
    preflight=preflight, evaluates_model=True, user_code=user_model, report=ANALYSES, analyses=analyses,
    figures=figures, shapes=shapes,
)
