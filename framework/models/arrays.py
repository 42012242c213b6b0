"""Modes of a whole population as arrays, for models that solve many points in one call.

A vectorized model may offer, next to ``modal_batch(thetas) -> list``, the method

    modal_arrays(theta (n, k), names (k,)) -> ModalArrays

which takes the parameter values as one matrix (columns named by ``names``, the other
parameters at their initial values) and returns frequencies (n, m) and shapes
(n, n_dof, m) without one Python object per point. The problem uses it on its in-process
path (:meth:`framework.updating.problem.UpdatingProblem.evaluate`); ``modal_batch`` stays the
protocol of every runner and must give the same numbers (build it from ``modal_arrays``,
as :class:`framework.structures.lab_frame.model.ThreeDofFrame` does).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from framework.core.errors import ModelEvaluationError
from framework.core.parameters import ParameterSet
from framework.models.base import ModalResult


@dataclass(frozen=True)
class ModalArrays:
    """Modes of n points: frequencies_hz (n, m), shapes (n, n_dof, m) at ``dofs``; ``errors``
    maps the index of a failed point to its :class:`ModelEvaluationError` (its rows are
    meaningless). A point with a non-finite frequency is failed here as in :class:`ModalResult`."""

    frequencies_hz: np.ndarray
    shapes: np.ndarray
    dofs: tuple[str, ...]
    errors: dict[int, ModelEvaluationError] = field(default_factory=dict)

    def __post_init__(self) -> None:
        f = np.asarray(self.frequencies_hz, dtype=float)
        s = np.asarray(self.shapes, dtype=float)
        n = f.shape[0]
        if f.ndim != 2 or s.shape != (n, len(self.dofs), f.shape[1]):
            raise ValueError(f"shapes {s.shape} do not match frequencies {f.shape} and {len(self.dofs)} dofs")
        errors = dict(self.errors)
        for i in np.flatnonzero(~np.all(np.isfinite(f), axis=1)):
            errors.setdefault(int(i), ModelEvaluationError("non_finite_frequency", f"frequencies {f[i].tolist()}"))
        object.__setattr__(self, "frequencies_hz", f)
        object.__setattr__(self, "shapes", s)
        object.__setattr__(self, "dofs", tuple(self.dofs))
        object.__setattr__(self, "errors", errors)

    def __len__(self) -> int:
        return int(self.frequencies_hz.shape[0])

    @property
    def ok(self) -> np.ndarray:
        """(n,) True where the point was solved."""
        ok = np.ones(len(self), dtype=bool)
        ok[list(self.errors)] = False
        return ok

    def result(self, i: int) -> ModalResult | ModelEvaluationError:
        """Point i as the per-point protocol has it (a ModalResult or the error)."""
        if i in self.errors:
            return self.errors[i]
        return ModalResult(self.frequencies_hz[i], self.shapes[i], self.dofs)

    def results(self) -> list:
        """Every point as ``modal_batch`` returns it."""
        return [self.result(i) for i in range(len(self))]


def theta_matrix(parameters: ParameterSet, theta: np.ndarray, names: Sequence[str]) -> dict[str, np.ndarray]:
    """Columns of every parameter of ``parameters`` for points ``theta`` (n, len(names)):
    the named columns, the others at their initial values; an unknown name raises KeyError."""
    theta = np.atleast_2d(np.asarray(theta, dtype=float))
    unknown = sorted(set(names) - set(parameters.names))
    if unknown:
        raise KeyError(f"unknown parameter(s) {unknown}; known: {parameters.names}")
    if theta.shape[1] != len(names):
        raise ValueError(f"theta has {theta.shape[1]} columns for {len(names)} names")
    cols = {p.name: np.full(theta.shape[0], float(p.initial)) for p in parameters}
    for j, name in enumerate(names):
        cols[name] = theta[:, j]
    return cols


def array_method(model):
    """``model.modal_arrays`` if it describes the model's own ``modal`` and ``modal_batch``, else None.

    A subclass that overrides ``modal`` or ``modal_batch`` but not ``modal_arrays`` (e.g. a
    fault-injection wrapper) is evaluated through ``modal_batch``, never past its override.
    """
    fn = getattr(model, "modal_arrays", None)
    if fn is None:
        return None
    mro = type(model).__mro__
    owner = next((c for c in mro if "modal_arrays" in c.__dict__), None)
    for name in ("modal", "modal_batch"):
        defining = next((c for c in mro if name in c.__dict__), None)
        if owner is None or defining is None or not issubclass(owner, defining):
            return None
    return fn
