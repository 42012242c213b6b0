"""Optimizer adapters, one module per method, all with the signature

    run(evaluator, seed, budget, **settings) -> Outcome

``run_optimizer(name, problem, seed, budget, runner=..., progress=..., **settings)``
creates the run's :class:`~framework.updating.evaluator.Evaluator` (count, best point, history,
failures, budget), dispatches to the adapter by name and builds the
:class:`OptimizerResult` from the evaluator; the problem itself is never changed, so one
problem serves any number of runs. ``settings_model(name)`` returns the pydantic settings
class (unknown keys rejected) used to validate configs.
"""

from __future__ import annotations

import importlib
import time
from collections.abc import Callable

from framework.core.errors import InputError
from framework.optimizers.base import Budget, OptimizerResult, build_result
from framework.updating.evaluator import Evaluator

#: name -> (module, settings class name)
OPTIMIZERS: dict[str, tuple[str, str]] = {
    "pso": ("framework.optimizers.pso", "PSOSettings"),
    "ga": ("framework.optimizers.ga", "GASettings"),
    "annealing": ("framework.optimizers.annealing", "AnnealingSettings"),
    "sm": ("framework.optimizers.sm", "SMSettings"),
    "snt": ("framework.optimizers.niching", "SNTSettings"),
    "nsga2": ("framework.optimizers.nsga2", "NSGA2Settings"),
    "hybrid": ("framework.optimizers.hybrid", "HybridSettings"),
    "multistart": ("framework.optimizers.multistart", "MultiStartSettings"),
}


def _module(name: str):
    if name not in OPTIMIZERS:
        raise InputError(f"unknown algorithm {name!r}; known: {sorted(OPTIMIZERS)}")
    return importlib.import_module(OPTIMIZERS[name][0])


def settings_model(name: str):
    """The pydantic settings class of optimizer ``name``."""
    return getattr(_module(name), OPTIMIZERS[name][1])


def run_optimizer(
    name: str,
    problem,
    seed: int,
    budget: Budget | None = None,
    *,
    runner=None,
    progress: Callable[[int], object] | None = None,
    pointwise: bool = False,
    **settings,
) -> OptimizerResult:
    """Run optimizer ``name`` on ``problem`` from ``seed`` within ``budget``.

    runner: how the model is evaluated (``runner(model, thetas) -> list``; serial when
    None); progress: called with the number of new model evaluations; pointwise: evaluate
    a population one point per call (same numbers, no vectorization).
    """
    module = _module(name)
    budget = budget or Budget()
    evaluator = Evaluator(problem, budget.max_evaluations, runner=runner, progress=progress, pointwise=pointwise)
    start = time.perf_counter()
    outcome = module.run(evaluator, seed, budget, **settings)
    return build_result(name, evaluator, seed, outcome, time.perf_counter() - start)


__all__ = ["Budget", "OptimizerResult", "OPTIMIZERS", "run_optimizer", "settings_model"]
