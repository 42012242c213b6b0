"""Study configuration: a YAML file validated by pydantic (unknown keys are rejected).

Example (studies/lab_frame.yaml)::

    study: lab_frame
    structure: {name: lab_frame_3dof}
    measured: {builtin: lab_frame, case: base}
    validation:                      # extra measured configurations, predicted, not fitted
      - {case: mass_0.654kg, structure_options: {case: mass_0.654kg},
         measured: {builtin: lab_frame, case: mass_0.654kg}}
    parameters: {names: null, bounds: {}}    # null: all of the structure's parameters
    objective: {alpha: 1.0, beta: 1.0}
    budget: {max_evaluations: 50000, stall_iterations: 10, stall_tolerance: 1.0e-8}
    algorithms:
      pso: {algorithm: pso, settings: {swarm_size: 20}}
      sm_initial: {algorithm: sm, settings: {start: initial}, runs: 1}
    runs: 10
    seed: 0
    sweep: {"algorithms.pso.settings.swarm_size": [5, 10, 20]}
    execution: {backend: serial, workers: 2}
    output: results/lab_frame

Overrides from the command line use dotted paths: ``--set algorithms.pso.settings.swarm_size=40``.
"""

from __future__ import annotations

import copy
import math
from pathlib import Path
from typing import Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from framework.errors import InputError
from framework.optimizers import OPTIMIZERS, Budget, settings_model


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class StructureConfig(_Strict):
    name: str
    options: dict[str, Any] = Field(default_factory=dict)


class MeasuredConfig(_Strict):
    """Either a built-in data set (``builtin`` + ``case``) or a file (YAML/CSV)."""

    builtin: str | None = None
    case: str = "base"
    file: str | None = None
    modes: list[int] | None = None  # 1-based subset of measured modes to use

    @model_validator(mode="after")
    def _one_source(self):
        if (self.builtin is None) == (self.file is None):
            raise ValueError("give exactly one of 'builtin' or 'file'")
        return self


class ValidationCase(_Strict):
    case: str
    structure_options: dict[str, Any] = Field(default_factory=dict)
    measured: MeasuredConfig


class ParametersConfig(_Strict):
    names: list[str] | None = None
    bounds: dict[str, tuple[float, float]] = Field(default_factory=dict)


class RatioConstraintConfig(_Strict):
    numerator: str
    denominator: str
    weight: float = Field(2e-4, ge=0)


class ObjectiveConfig(_Strict):
    alpha: float = Field(1.0, ge=0)
    beta: float = Field(1.0, ge=0)
    use_shapes: bool = True
    pairing: Literal["mac", "order", "frequency"] = "mac"
    mac_threshold: float = Field(0.5, ge=0, le=1)
    frequency_window: float | None = Field(None, gt=0)
    unmatched_penalty: float = Field(1.0, ge=0)
    failure_penalty: float = Field(1e3, gt=0)
    ratio_constraints: list[RatioConstraintConfig] = Field(default_factory=list)
    regularization_tau: float = Field(0.0, ge=0)
    regularization_space: Literal["ratio", "normalized"] = "ratio"
    formulation: str = "spec"
    options: dict[str, Any] = Field(default_factory=dict)


class AlgorithmConfig(_Strict):
    algorithm: str
    settings: dict[str, Any] = Field(default_factory=dict)
    runs: int | None = Field(None, ge=1)
    budget: dict[str, Any] = Field(default_factory=dict)

    @field_validator("algorithm")
    @classmethod
    def _known(cls, v: str) -> str:
        if v not in OPTIMIZERS:
            raise ValueError(f"unknown algorithm {v!r}; known: {sorted(OPTIMIZERS)}")
        return v

    @model_validator(mode="after")
    def _settings_valid(self):
        model = settings_model(self.algorithm)
        try:
            model(**self.settings)
        except ValidationError as exc:
            first = exc.errors()[0]
            loc = ".".join(str(p) for p in first["loc"])
            msg = "unknown key" if first["type"] == "extra_forbidden" else first["msg"]
            raise ValueError(
                f"settings.{loc}: {msg} (value {first.get('input')!r}) for algorithm {self.algorithm!r}"
            ) from None
        try:
            Budget(**self.budget)
        except ValidationError as exc:
            first = exc.errors()[0]
            raise ValueError(f"budget.{'.'.join(map(str, first['loc']))}: {first['msg']}") from None
        return self


class ExecutionConfig(_Strict):
    backend: Literal["serial", "processes", "dask"] = "serial"
    workers: int = Field(2, ge=1)
    scheduler: str | None = None
    evaluation_backend: Literal["serial", "processes", "dask"] = "serial"
    progress: bool = True
    progress_evaluations: bool = False


class StudyConfig(_Strict):
    study: str
    description: str = ""
    kind: str = "updating"
    structure: StructureConfig
    measured: MeasuredConfig
    validation: list[ValidationCase] = Field(default_factory=list)
    parameters: ParametersConfig = Field(default_factory=ParametersConfig)
    objective: ObjectiveConfig = Field(default_factory=ObjectiveConfig)
    budget: Budget = Field(default_factory=Budget)
    algorithms: dict[str, AlgorithmConfig]
    runs: int = Field(10, ge=1)
    seed: int = Field(0, ge=0)
    sweep: dict[str, list[Any]] = Field(default_factory=dict)
    execution: ExecutionConfig = Field(default_factory=ExecutionConfig)
    output: str | None = None
    options: dict[str, Any] = Field(default_factory=dict)

    @field_validator("algorithms")
    @classmethod
    def _non_empty(cls, v):
        if not v:
            raise ValueError("at least one algorithm is required")
        return v

    @field_validator("sweep")
    @classmethod
    def _sweep_lists(cls, v):
        for key, values in v.items():
            if not values:
                raise ValueError(f"sweep {key!r} has no values")
        return v

    def output_dir(self, root: Path | None = None) -> Path:
        out = Path(self.output or f"results/{self.study}")
        return out if out.is_absolute() or root is None else root / out


# --------------------------------------------------------------------------------------
def parse_value(text: str) -> Any:
    """A --set value: YAML scalar/list syntax (``40``, ``1e-6``, ``[5, 10]``, ``true``)."""
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError:
        return text


def set_path(data: dict, dotted: str, value: Any) -> None:
    """Set ``data[a][b][c] = value`` for ``dotted = 'a.b.c'`` (creating mappings)."""
    keys = dotted.split(".")
    node = data
    for key in keys[:-1]:
        if not isinstance(node.get(key), dict):
            node[key] = {}
        node = node[key]
    node[keys[-1]] = value


def format_error(exc: ValidationError, source: str) -> str:
    """One line per pydantic error: '<source>: <field path>: <message> (value: ...)'."""
    lines = []
    for err in exc.errors():
        loc = ".".join(str(p) for p in err["loc"])
        value = err.get("input")
        shown = "" if isinstance(value, dict) else f" (value: {value!r})"
        msg = err["msg"].removeprefix("Value error, ")
        if err["type"] == "extra_forbidden":
            msg = "unknown key"
        lines.append(f"{source}: {loc}: {msg}{shown}")
    return "\n".join(lines)


def validate(data: dict, source: str = "<config>", base_dir: Path | None = None) -> StudyConfig:
    """Validate a config mapping; raise InputError naming file, field and value."""
    if not isinstance(data, dict):
        raise InputError(f"{source}: a study config must be a mapping, got {type(data).__name__}")
    try:
        cfg = StudyConfig.model_validate(data)
    except ValidationError as exc:
        raise InputError(format_error(exc, source)) from None
    for name, (lo, hi) in cfg.parameters.bounds.items():
        if not (math.isfinite(lo) and math.isfinite(hi)):
            raise InputError(f"{source}: parameters.bounds.{name}: bounds must be finite, got [{lo}, {hi}]")
        if lo > hi:
            raise InputError(f"{source}: parameters.bounds.{name}: bounds are swapped: [{lo}, {hi}]")
        if lo == hi:
            raise InputError(f"{source}: parameters.bounds.{name}: bounds are empty: [{lo}, {hi}]")
    files = [("measured.file", cfg.measured)] + [
        (f"validation[{i}].measured.file", v.measured) for i, v in enumerate(cfg.validation)
    ]
    for field_name, measured in files:
        if measured.file is None:
            continue
        path = Path(measured.file)
        if (
            not path.is_absolute()
            and not path.exists()
            and base_dir is not None
            and (base_dir / path).exists()
        ):
            path = base_dir / path
        if not path.exists():
            raise InputError(f"{source}: {field_name}: file not found: {measured.file}")
        measured.file = str(path)
    return cfg


def read_with_overrides(path: str | Path, overrides: list[str] | None = None, what: str = "config") -> dict:
    """Read a YAML mapping and apply ``key.path=value`` overrides (errors name the file)."""
    path = Path(path)
    if not path.exists():
        raise InputError(f"{what} file not found: {path}")
    try:
        data = yaml.safe_load(path.read_text())
    except yaml.YAMLError as exc:
        raise InputError(f"{path}: not valid YAML: {exc}") from None
    if data is None:
        raise InputError(f"{path}: {what} file is empty")
    if not isinstance(data, dict):
        raise InputError(f"{path}: a {what} must be a mapping, got {type(data).__name__}")
    data = copy.deepcopy(data)
    for item in overrides or []:
        if "=" not in item:
            raise InputError(f"--set {item!r}: expected KEY.PATH=VALUE")
        key, value = item.split("=", 1)
        set_path(data, key.strip(), parse_value(value))
    return data


def load(path: str | Path, overrides: list[str] | None = None) -> StudyConfig:
    """Read a YAML config, apply ``key.path=value`` overrides, validate."""
    path = Path(path)
    data = read_with_overrides(path, overrides)
    return validate(data, source=str(path), base_dir=path.parent)


_format_error = format_error  # backwards-compatible private name
