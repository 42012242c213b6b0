"""Residual formulations, registered as typed objects (:class:`Formulation`): ``spec`` (SPEC 3:
relative frequency errors and a MAC term), ``reference`` (the SMU benchmarks: eigenvalue
differences and a MAC or eigenvector-difference term) and ``gaussian`` (residuals whitened by
the data's noise). Each says how its residuals relate to the data noise (``residual_std``),
which the likelihood uses. A new formulation is a module here and one entry of
:data:`FORMULATIONS`."""

from framework.core.errors import InputError
from framework.updating.formulations.base import Formulation, ResidualStd
from framework.updating.formulations.gaussian import GAUSSIAN
from framework.updating.formulations.reference import REFERENCE
from framework.updating.formulations.spec import SPEC

#: every selectable formulation by name
FORMULATIONS: dict[str, Formulation] = {f.name: f for f in (SPEC, REFERENCE, GAUSSIAN)}

__all__ = ["FORMULATIONS", "Formulation", "ResidualStd", "get_formulation"]


def get_formulation(name: str) -> Formulation:
    """The formulation called ``name`` (one of :data:`FORMULATIONS`)."""
    if name not in FORMULATIONS:
        raise InputError(f"objective.formulation {name!r} unknown; known: {sorted(FORMULATIONS)}")
    return FORMULATIONS[name]
