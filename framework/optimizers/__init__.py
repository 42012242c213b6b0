"""Optimizer adapters, one module per method, all with the signature

    run(problem, seed, budget, **settings) -> OptimizerResult

``run_optimizer(name, ...)`` dispatches by name; ``settings_model(name)`` returns the
pydantic settings class (unknown keys rejected) used to validate configs.
"""

from __future__ import annotations

import importlib

from framework.errors import InputError
from framework.optimizers.base import Budget, OptimizerResult

#: name -> (module, settings class name)
OPTIMIZERS: dict[str, tuple[str, str]] = {
    "pso": ("framework.optimizers.pso", "PSOSettings"),
    "ga": ("framework.optimizers.ga", "GASettings"),
    "annealing": ("framework.optimizers.annealing", "AnnealingSettings"),
    "sm": ("framework.optimizers.sensitivity", "SMSettings"),
    "snt": ("framework.optimizers.niching", "SNTSettings"),
    "nsga2": ("framework.optimizers.nsga2", "NSGA2Settings"),
}


def _module(name: str):
    if name not in OPTIMIZERS:
        raise InputError(f"unknown algorithm {name!r}; known: {sorted(OPTIMIZERS)}")
    return importlib.import_module(OPTIMIZERS[name][0])


def settings_model(name: str):
    """The pydantic settings class of optimizer ``name``."""
    return getattr(_module(name), OPTIMIZERS[name][1])


def run_optimizer(name: str, problem, seed: int, budget: Budget | None = None, **settings) -> OptimizerResult:
    """Run optimizer ``name`` on ``problem`` from ``seed`` within ``budget``."""
    return _module(name).run(problem, seed, budget or Budget(), **settings)


__all__ = ["Budget", "OptimizerResult", "OPTIMIZERS", "run_optimizer", "settings_model"]
