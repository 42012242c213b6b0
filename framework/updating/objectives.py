"""The objective's settings (``ObjectiveSpec``, the config section ``objective:``) and the
penalty terms every formulation shares, as a residual vector first.

A formulation (:mod:`framework.updating.formulations`: ``spec``, the SPEC 3 frequency + MAC
objective; ``reference``, the SMU benchmarks'; ``gaussian``, whitened residuals) maps (modal
result, measured modes, spec) to the modal residuals r; the problem appends the penalty terms,
so that Pi = sum r^2 and the scalar objective, the residual vector (least squares, sensitivity
method) and the objective vector (NSGA-II) are three views of one definition.

- A failed model evaluation has every residual equal to sqrt(failure_penalty / r), so
  Pi = failure_penalty (default 1e3, far above any physical misfit).
- Penalty terms (appended residuals):
  ratio constraint   sqrt(w |theta_a/theta_b - theta_a,0/theta_b,0|)   (bridge soft constraint)
  regularization     sqrt(tau) (z - z_0), z the parameters as ratios to initial values
                     ("ratio") or normalized to their bounds ("normalized")  (Tikhonov)

Exact Jacobian of the penalty terms: :func:`penalty_jacobian` (the formulations' own are in
their modules; :meth:`framework.updating.problem.UpdatingProblem.jacobian` joins them).
"""

from __future__ import annotations

from typing import Annotated, Any, ClassVar, Literal

import numpy as np
from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    StrictBool,
    StrictStr,
    ValidationError,
    ValidationInfo,
    field_validator,
    model_validator,
)

from framework.core.errors import InputError
from framework.core.parameters import ParameterSet
from framework.updating.formulations import FORMULATIONS, get_formulation


def _no_bool(value):
    """Reject booleans and text where a number is expected (pydantic would read True as 1.0
    and '1' as 1.0)."""
    if isinstance(value, bool | str | bytes):
        raise ValueError(f"expected a number, got {value!r}")
    return value


Number = Annotated[float, BeforeValidator(_no_bool)]


class _Frozen(BaseModel):
    """Frozen pydantic model that accepts positional fields and raises InputError naming the field.

    Nested in a config, pydantic validates it directly (a ``ValidationError`` whose location
    names the field); constructed in Python (``ObjectiveSpec(alpha=...)``) a bad value raises
    :class:`~framework.core.errors.InputError` "objective.<field>: <message> (value ...)".
    """

    model_config = ConfigDict(frozen=True, extra="forbid")
    _where: ClassVar[str] = "objective"

    def __init__(self, *args, **kwargs):
        names = list(type(self).model_fields)
        if len(args) > len(names):
            raise InputError(f"{self._where}: at most {len(names)} positional values, got {len(args)}")
        for name, value in zip(names, args):
            if name in kwargs:
                raise InputError(f"{self._where}.{name}: given twice")
            kwargs[name] = value
        try:
            super().__init__(**kwargs)
        except ValidationError as exc:
            raise InputError(validation_message(exc, self._where)) from None

    # pydantic calls a custom __init__ also when it validates the model nested in another
    # (a config); this flag keeps nested validation on pydantic's own path, so that a
    # config error stays a ValidationError located at its field
    __init__.__pydantic_base_init__ = True  # type: ignore[attr-defined]


def validation_message(exc: ValidationError, where: str) -> str:
    """One line naming the field, the problem and the value of a pydantic error."""
    first = exc.errors()[0]
    loc = ".".join(str(p) for p in (where, *first["loc"]) if p != "")
    msg = "unknown key" if first["type"] == "extra_forbidden" else first["msg"].removeprefix("Value error, ")
    if not first["loc"]:  # a rule over several fields: the input is the whole mapping
        return f"{loc}: {msg}"
    return f"{loc}: {msg} (value {first.get('input')!r})"


class RatioConstraint(_Frozen):
    """Soft constraint w |theta_a/theta_b - theta_a,0/theta_b,0| (SPEC 3, bridge: w = 2e-4)."""

    _where: ClassVar[str] = "objective.ratio_constraints"

    numerator: str
    denominator: str
    weight: Number = Field(2e-4, ge=0, allow_inf_nan=False)


class ObjectiveSpec(_Frozen):
    """Settings of the objective, and the config schema of ``objective:``.

    alpha/beta weight the frequency and MAC terms (not both 0: Pi would be identically 0).
    pairing: "mac" (highest MAC, one-to-one), "order" or "frequency"; mac_threshold: a
    pair below it is unmatched; frequency_window: relative window for MAC pairing
    (None = any); use_shapes: include the MAC term (needs measured shapes);
    unmatched_penalty: Pi added per unmatched mode; failure_penalty (> 0): Pi of a failed
    evaluation; ratio_constraints, regularization_tau (Tikhonov weight) and
    regularization_space ("ratio" or "normalized"): penalty terms; formulation: a name of
    :data:`framework.updating.formulations.FORMULATIONS`, whose ``options`` are checked here.
    """

    alpha: Number = Field(1.0, ge=0, allow_inf_nan=False)
    beta: Number = Field(1.0, ge=0, allow_inf_nan=False)
    use_shapes: StrictBool = True
    pairing: Literal["mac", "order", "frequency"] = "mac"
    mac_threshold: Number = Field(0.5, ge=0, le=1)
    frequency_window: Number | None = Field(None, gt=0, allow_inf_nan=False)
    unmatched_penalty: Number = Field(1.0, ge=0, allow_inf_nan=False)
    failure_penalty: Number = Field(1e3, gt=0, allow_inf_nan=False)
    ratio_constraints: tuple[RatioConstraint, ...] = ()
    regularization_tau: Number = Field(0.0, ge=0, allow_inf_nan=False)
    regularization_space: Literal["ratio", "normalized"] = "ratio"
    formulation: StrictStr = "spec"
    options: dict[str, Any] = Field(default_factory=dict)

    @field_validator("formulation")
    @classmethod
    def _known_formulation(cls, name: str) -> str:
        if name not in FORMULATIONS:
            raise ValueError(f"unknown formulation {name!r}; known: {sorted(FORMULATIONS)}")
        return name

    @field_validator("options")
    @classmethod
    def _formulation_options(cls, options: dict, info: ValidationInfo) -> dict:
        name = info.data.get("formulation")
        if name is not None:  # else the formulation itself was rejected
            check = get_formulation(name).check_options
            if check is not None:
                check(options)
        return options

    @model_validator(mode="after")
    def _not_identically_zero(self):
        if self.alpha == 0 and self.beta == 0:
            raise ValueError("alpha and beta are both 0: the objective would be identically 0")
        return self


def penalty_residuals(
    theta: np.ndarray, x: np.ndarray, parameters: ParameterSet, spec: ObjectiveSpec
) -> np.ndarray:
    """Residuals of the ratio constraints and the Tikhonov term for points theta (n, k)."""
    theta = np.atleast_2d(theta)
    x = np.atleast_2d(x)
    parts = []
    names = parameters.names
    for c in spec.ratio_constraints:
        a, b = names.index(c.numerator), names.index(c.denominator)
        r0 = parameters.initial[a] / parameters.initial[b]
        d = np.abs(theta[:, a] / theta[:, b] - r0)
        parts.append(np.sqrt(c.weight * d)[:, None])
    if spec.regularization_tau > 0:
        if spec.regularization_space == "ratio":
            z = parameters.to_ratio(theta)
            z0 = np.ones(len(parameters))
        else:
            z, z0 = x, parameters.x_initial
        parts.append(np.sqrt(spec.regularization_tau) * (z - z0))
    if not parts:
        return np.zeros((theta.shape[0], 0))
    return np.concatenate(parts, axis=1)


def penalty_jacobian(theta: np.ndarray, parameters: ParameterSet, spec: ObjectiveSpec) -> np.ndarray:
    """d (penalty residuals) / d theta (n_pen, k) at one point theta (k,).

    Ratio constraint r = sqrt(w |d|), d = theta_a/theta_b - r_0: dr = sqrt(w) sign(d) dd / (2 sqrt|d|)
    with dd/dtheta_a = 1/theta_b, dd/dtheta_b = -theta_a/theta_b^2 (not differentiable at d = 0,
    where the zero subgradient is used). Tikhonov: sqrt(tau)/theta_0,j ("ratio") or
    sqrt(tau)/(upper_j - lower_j) ("normalized") on the diagonal.
    """
    theta = np.asarray(theta, float)
    k = theta.size
    names = parameters.names
    rows = []
    for c in spec.ratio_constraints:
        a, b = names.index(c.numerator), names.index(c.denominator)
        d = theta[a] / theta[b] - parameters.initial[a] / parameters.initial[b]
        row = np.zeros(k)
        if d != 0.0:
            scale = np.sqrt(c.weight) * np.sign(d) / (2.0 * np.sqrt(abs(d)))
            row[a] += scale / theta[b]
            row[b] -= scale * theta[a] / theta[b] ** 2
        rows.append(row[None, :])
    if spec.regularization_tau > 0:
        if spec.regularization_space == "ratio":
            with np.errstate(divide="ignore"):
                diag = np.where(parameters.initial != 0, 1.0 / parameters.initial, np.nan)
        else:
            diag = 1.0 / (parameters.upper - parameters.lower)
        rows.append(np.sqrt(spec.regularization_tau) * np.diag(diag))
    if not rows:
        return np.zeros((0, k))
    return np.concatenate(rows, axis=0)


def n_penalty_residuals(parameters: ParameterSet, spec: ObjectiveSpec) -> int:
    return len(spec.ratio_constraints) + (len(parameters) if spec.regularization_tau > 0 else 0)


def check_constraints(parameters: ParameterSet, spec: ObjectiveSpec) -> None:
    """Ratio constraints must name updated parameters."""
    for c in spec.ratio_constraints:
        for name in (c.numerator, c.denominator):
            if name not in parameters.names:
                raise InputError(
                    f"objective.ratio_constraints: parameter {name!r} is not updated; updated: {parameters.names}"
                )
