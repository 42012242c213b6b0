"""Optimizers: one adapter module per method, each registered once as a typed
:class:`~framework.optimizers.base.Optimizer` (name, pydantic settings class, adapter
``run(evaluator, seed, budget, settings) -> Outcome``) in :data:`OPTIMIZERS`.

``run_optimizer(name, problem, seed, budget, settings=..., runner=..., progress=...)`` creates
the run's :class:`~framework.updating.evaluator.Evaluator` (count, best point, history,
failures, budget), calls the adapter and builds the :class:`OptimizerResult` from the
evaluator; the problem itself is never changed, so one problem serves any number of runs.
Settings are validated once: a config's by :meth:`Optimizer.validate` when the config is read
(they then travel typed to the adapter), keywords given in code by ``run_optimizer``. A new
optimizer is a module ``framework/optimizers/<name>.py`` with its ``Settings`` subclass, its
``run`` and ``OPTIMIZER = Optimizer(name, settings, run)``, and one line in :data:`OPTIMIZERS`.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from typing import Any

from framework.core.errors import InputError
from framework.optimizers import annealing, ga, hybrid, multistart, niching, nsga2, pso, sm
from framework.optimizers.base import Budget, Optimizer, OptimizerResult, Settings, build_result
from framework.updating.evaluator import Evaluator

OPTIMIZERS: dict[str, Optimizer] = {o.name: o for o in (
    pso.OPTIMIZER,
    ga.OPTIMIZER,
    annealing.OPTIMIZER,
    sm.OPTIMIZER,
    niching.OPTIMIZER,
    nsga2.OPTIMIZER,
    hybrid.OPTIMIZER,
    multistart.OPTIMIZER,
)}


def get_optimizer(name: str) -> Optimizer:
    """The optimizer ``name``; InputError naming the known ones."""
    if name not in OPTIMIZERS:
        raise InputError(f"unknown algorithm {name!r}; known: {sorted(OPTIMIZERS)}")
    return OPTIMIZERS[name]


def run_optimizer(
    name: str,
    problem,
    seed: int,
    budget: Budget | None = None,
    *,
    settings: Settings | Mapping[str, Any] | None = None,
    runner=None,
    progress: Callable[[int], object] | None = None,
    pointwise: bool = False,
    **options,
) -> OptimizerResult:
    """Run optimizer ``name`` on ``problem`` from ``seed`` within ``budget``.

    settings: the optimizer's settings object (as validated from a config, used as it is), or
    give them as keywords (``swarm_size=40``), validated here; runner: how the model is
    evaluated (``runner(model, thetas) -> list``; serial when None); progress: called with the
    number of new model evaluations; pointwise: evaluate a population one point per call
    (same numbers, no vectorization).
    """
    optimizer = get_optimizer(name)
    if settings is not None and options:
        raise TypeError(f"run_optimizer({name!r}): give the settings either as settings= or as keywords, not both")
    if not isinstance(settings, optimizer.settings):
        settings = optimizer.settings(**(settings or options))
    budget = budget or Budget()
    evaluator = Evaluator(problem, budget.max_evaluations, runner=runner, progress=progress, pointwise=pointwise)
    start = time.perf_counter()
    outcome = optimizer.run(evaluator, seed, budget, settings)
    return build_result(name, evaluator, seed, outcome, time.perf_counter() - start)


__all__ = ["Budget", "OPTIMIZERS", "Optimizer", "OptimizerResult", "Settings", "get_optimizer", "run_optimizer"]
