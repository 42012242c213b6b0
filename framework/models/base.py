"""What every structural model provides.

A structural model is a pure function of its parameters: ``modal(theta)`` builds the
model from scratch for the physical parameter values ``theta`` (a {name: value} dict)
and returns a :class:`ModalResult` with frequencies and mode shapes read at the model's
measurable DOFs. Nothing survives between calls, so a model is picklable and can be
evaluated in any process. A failed evaluation raises
:class:`framework.core.errors.ModelEvaluationError` with a reason.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

from framework.core.errors import ModelEvaluationError
from framework.core.parameters import ParameterSet


@dataclass(frozen=True)
class ModalResult:
    """Modes of a model: frequencies_hz (n,), shapes (n_dof, n) at ``dofs``.

    ``mode_info`` holds optional per-mode arrays of length n (e.g. kinetic-energy share
    of the deck, a mode-type label); ``meta`` holds anything else (e.g. cable forces).
    """

    frequencies_hz: np.ndarray
    shapes: np.ndarray
    dofs: tuple[str, ...]
    mode_info: Mapping[str, np.ndarray] = field(default_factory=dict)
    meta: Mapping[str, object] = field(default_factory=dict)

    def __post_init__(self) -> None:
        f = np.asarray(self.frequencies_hz, dtype=float)
        s = np.asarray(self.shapes, dtype=float)
        object.__setattr__(self, "frequencies_hz", f)
        object.__setattr__(self, "shapes", s)
        object.__setattr__(self, "dofs", tuple(self.dofs))
        if s.ndim != 2 or s.shape != (len(self.dofs), f.size):
            raise ModelEvaluationError(
                "bad_modal_result",
                f"shapes {s.shape} do not match ({len(self.dofs)} dofs, {f.size} modes)",
            )
        if not np.all(np.isfinite(f)):
            raise ModelEvaluationError("non_finite_frequency", f"frequencies {f.tolist()}")

    @property
    def n_modes(self) -> int:
        return int(self.frequencies_hz.size)

    def at(self, dofs: Sequence[str]) -> np.ndarray:
        """Shapes restricted to ``dofs`` (rows in that order)."""
        index = {d: i for i, d in enumerate(self.dofs)}
        missing = [d for d in dofs if d not in index]
        if missing:
            raise KeyError(f"model has no DOF(s) {missing}; known DOFs: {list(self.dofs)}")
        return self.shapes[[index[d] for d in dofs], :]


@runtime_checkable
class StructuralModel(Protocol):
    """Protocol of a structural model.

    parameters: the structure's updatable parameters with initial values and default
    bounds (studies may pick a subset or change bounds). dofs: labels of the DOFs at
    which shapes are returned. modal(theta): modes for parameter values ``theta``
    (parameters not given keep their initial values).

    Optional, for exact Jacobians (:mod:`framework.core.modal_derivatives`):
    ``modal_derivatives(theta, result=None, *, parameters=None, modes=None)`` ->
    ModalDerivatives (d lambda / d theta and d phi / d theta of the mass-normalized shapes at
    ``dofs``; raises CloseEigenvalues for a repeated or close eigenvalue) and
    ``derivative_cost(n_modes, n_params)`` -> its cost in eigen-solve equivalents.
    """

    @property
    def parameters(self) -> ParameterSet: ...

    @property
    def dofs(self) -> tuple[str, ...]: ...

    def modal(self, theta: Mapping[str, float]) -> ModalResult: ...


def modal_many(model: StructuralModel, thetas: Sequence[Mapping[str, float]]) -> list:
    """Evaluate many points; uses ``model.modal_batch`` when the model is vectorized.

    Returns a list whose items are ModalResult or ModelEvaluationError (never raises for
    a failed point).
    """
    batch = getattr(model, "modal_batch", None)
    if batch is not None:
        return list(batch(thetas))
    out: list = []
    for theta in thetas:
        out.append(safe_modal(model, theta))
    return out


def safe_modal(model: StructuralModel, theta: Mapping[str, float]):
    """model.modal(theta), with any failure returned as a ModelEvaluationError.

    ``sys.exit()`` in a user's code becomes the failure "model_exit" instead of ending the
    process; KeyboardInterrupt still propagates (Ctrl-C stops a study). Native crashes and
    hangs cannot be caught in-process: see :mod:`framework.execution.isolation`.
    """
    try:
        return model.modal(theta)
    except ModelEvaluationError as exc:
        return exc
    except SystemExit as exc:
        return ModelEvaluationError("model_exit", f"the model called sys.exit({exc.code!r})")
    except (np.linalg.LinAlgError, ArithmeticError) as exc:
        return ModelEvaluationError("singular_matrix", f"{type(exc).__name__}: {exc}")
    except Exception as exc:  # a user's build function can raise anything
        return ModelEvaluationError("model_error", f"{type(exc).__name__}: {exc}")


def full_theta(parameters: ParameterSet, theta: Mapping[str, float]) -> dict[str, float]:
    """Initial values of all parameters, overridden by ``theta``; unknown names rejected."""
    unknown = sorted(set(theta) - set(parameters.names))
    if unknown:
        raise KeyError(f"unknown parameter(s) {unknown}; known: {parameters.names}")
    values = {p.name: float(p.initial) for p in parameters}
    values.update({k: float(v) for k, v in theta.items()})
    return values
