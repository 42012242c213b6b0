"""What every study config has, whatever its run kind (the header), and shared sections.

A study config is one YAML mapping: the header fields below plus the fields of its run kind
(``kind: updating`` by default; see :mod:`framework.study.kinds`). Each kind's schema
subclasses :class:`StudyHeader`, so unknown keys are rejected with their path and every
value is checked with strict types (``runs: true`` is not 1, ``seed: 1e23`` is not a seed).

Header fields:
- ``study``: name (letters, digits, ``_ . -``); results go to ``results/<study>`` unless
  ``output`` says otherwise;
- ``kind``: run kind; ``description``: free text;
- ``runs``, ``seed``: runs per entry and the first seed (run i uses ``seed + i``);
- ``sweep``: ``{dotted.path: [values]}``, every combination is a variant;
- ``variants``: ``{name: {dotted.path: value}}``, named sets of overrides (combined with
  the sweep grid), e.g. the same study on two structures;
- ``execution``: how runs and evaluations are executed (never part of a run's identity);
- ``report``: options of the analyses and figures drawn from the tables (never part of a
  run's identity: changing them keeps every stored run).
"""

from __future__ import annotations

import re
from typing import Annotated, Any, Literal

from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    PrivateAttr,
    StrictBool,
    StrictInt,
    ValidationError,
    field_validator,
)

from framework.core.errors import InputError

#: upper limits that keep a config from asking for more than a machine can plan
MAX_RUNS_PER_ENTRY = 100_000
MAX_PLANNED_RUNS = 200_000
NAME_PATTERN = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.+\-]*$")
#: a Dask scheduler address: [protocol://]host:port
SCHEDULER_PATTERN = re.compile(r"^(?:[a-z][a-z0-9+]*://)?[A-Za-z0-9_.\-\[\]:]+:[0-9]{1,5}$")


class Strict(BaseModel):
    """Base of every config section: unknown keys rejected, values not coerced across types."""

    model_config = ConfigDict(extra="forbid", strict=True, validate_default=True)


def _number(value):
    """A number where a float is expected: int or float, never a boolean or text."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"expected a number, got {value!r}")
    return float(value)


#: a float field of a config: ints accepted, booleans and text refused
Number = Annotated[float, BeforeValidator(_number)]

#: wall-time limit (s) of one isolated model evaluation when the config gives none: a hang
#: becomes a "timeout" failure of that evaluation instead of a study that never ends
DEFAULT_EVALUATION_TIMEOUT_S = 600.0


class ExecutionConfig(Strict):
    """Where runs and model evaluations execute. Results do not depend on any of these."""

    backend: Literal["serial", "processes", "dask"] = "serial"
    workers: StrictInt = Field(2, ge=1, le=1024)
    scheduler: str | None = None
    evaluation_backend: Literal["serial", "processes", "dask"] = "serial"
    #: evaluate the model in an isolated worker process, so that a crash, ``sys.exit`` or hang
    #: of the model becomes a recorded failure of that evaluation: true, false, or "auto"
    #: (isolated exactly when the structure is user code: ``module:function`` outside ``framework``)
    isolate: StrictBool | Literal["auto"] = "auto"
    #: wall-time limit of one model evaluation in seconds (implies isolation); isolated
    #: evaluations without one get DEFAULT_EVALUATION_TIMEOUT_S
    evaluation_timeout_s: Number | None = Field(None, gt=0, le=86_400, allow_inf_nan=False)
    progress: StrictBool = True
    progress_evaluations: StrictBool = False

    @field_validator("scheduler")
    @classmethod
    def _address(cls, v):
        if v is not None and not SCHEDULER_PATTERN.match(v):
            raise ValueError(f"a Dask scheduler address is [tcp://]host:port, got {v!r}")
        return v


def evaluation_isolation(execution: dict, names_code: bool) -> tuple[bool, float | None]:
    """(isolate, timeout_s) of a run's model evaluations from its ``execution`` section.

    ``isolate: auto`` isolates when the structure is user code (``names_code``); an isolated
    evaluation without ``evaluation_timeout_s`` gets :data:`DEFAULT_EVALUATION_TIMEOUT_S`;
    a timeout implies isolation."""
    isolate = execution.get("isolate", "auto")
    timeout = execution.get("evaluation_timeout_s")
    isolate = names_code if isolate == "auto" else bool(isolate)
    if timeout is not None:
        return True, float(timeout)
    return isolate, (DEFAULT_EVALUATION_TIMEOUT_S if isolate else None)


class StudyHeader(Strict):
    study: str = Field(min_length=1, max_length=120)
    description: str = ""
    kind: str = "updating"
    runs: StrictInt = Field(10, ge=1, le=MAX_RUNS_PER_ENTRY)
    seed: StrictInt = Field(0, ge=0, le=2**32 - 1)
    sweep: dict[str, list[Any]] = Field(default_factory=dict)
    variants: dict[str, dict[str, Any]] = Field(default_factory=dict)
    execution: ExecutionConfig = Field(default_factory=ExecutionConfig)
    output: str | None = None
    report: dict[str, Any] = Field(default_factory=dict)
    #: the config file this was read from (named in the errors found after validation)
    _source: str = PrivateAttr(default="")

    @field_validator("study")
    @classmethod
    def _safe_name(cls, v: str) -> str:
        if not NAME_PATTERN.match(v) or ".." in v:
            raise ValueError(
                "study name must be letters, digits and _ . + - (no path separators or '..'), "
                f"got {v!r}"
            )
        return v

    @field_validator("sweep")
    @classmethod
    def _sweep_lists(cls, v):
        for key, values in v.items():
            if not values:
                raise ValueError(f"sweep {key!r} has no values")
        return v

    @field_validator("variants")
    @classmethod
    def _variant_names(cls, v):
        for name in v:
            if not NAME_PATTERN.match(name):
                raise ValueError(f"variant name {name!r} must be letters, digits and _ . + -")
        return v

    def output_dir(self, root=None):
        from pathlib import Path

        out = Path(self.output or f"results/{self.study}")
        return out if out.is_absolute() or root is None else Path(root) / out


#: header fields that never change a run's result (left out of run identities)
NON_IDENTITY_FIELDS = ("study", "description", "runs", "seed", "sweep", "variants", "execution", "output", "report")


def format_error(exc: ValidationError, source: str) -> str:
    """One line naming the first problem: '<source>: <field path>: <message> (value: ...)',
    followed by how many more problems there are."""
    errors = exc.errors()
    err = errors[0]
    loc = ".".join(str(p) for p in err["loc"])
    value = err.get("input")
    shown = "" if isinstance(value, dict) else f" (value: {_short(value)})"
    msg = " ".join(err["msg"].removeprefix("Value error, ").split())
    if err["type"] == "extra_forbidden":
        msg = "unknown key"
    more = f" (and {len(errors) - 1} more problem{'s' * (len(errors) > 2)})" if len(errors) > 1 else ""
    return f"{source}: {loc}: {msg}{shown}{more}"


def _short(value: Any, limit: int = 80) -> str:
    try:
        text = repr(value)
    except ValueError:  # an integer too long to print
        text = f"<{type(value).__name__}>"
    return text if len(text) <= limit else text[: limit - 3] + "..."


def validated(model: type[BaseModel], data: Any, source: str, context: dict | None = None):
    """``model.model_validate(data)``; errors become one InputError naming file, field, value."""
    try:
        return model.model_validate(data, context=context)
    except ValidationError as exc:
        raise InputError(format_error(exc, source)) from None
