"""Particle swarm optimization on pyswarms' backend (global-best star topology).

Velocity and position updates (pyswarms ``Star`` topology):

    v <- w v + c1 r1 (p_best - x) + c2 r2 (g_best - x),    x <- x + v

in normalized coordinates. Source settings (SPEC 4): (w, c1, c2) = factor x (0.729, 1.5,
1.5) with factor 0.75, swarm of 20, velocity clamped to (upper - lower)/2 = 0.5, particles
leaving the box put back on the boundary (pyswarms ``nearest`` strategy). Linearly
decreasing inertia (w -> w_end over ``max_iterations``) is an option. The loop is ours so
that the whole swarm is evaluated in one call (batch/parallel) and the SPEC termination
rule applies; pyswarms draws from numpy's global generator, which is seeded from the run's
seed and restored afterwards (:func:`seeded_global_numpy`).
"""

from __future__ import annotations

import contextlib
import logging
from typing import Literal

import numpy as np
from pydantic import Field

from framework.optimizers.base import Budget, Optimizer, Outcome, Settings, Termination, seeded_global_numpy


class PSOSettings(Settings):
    swarm_size: int = Field(20, ge=2)
    factor: float = Field(0.75, gt=0)
    inertia: float = Field(0.729, ge=0)
    c1: float = Field(1.5, ge=0)
    c2: float = Field(1.5, ge=0)
    inertia_schedule: Literal["constant", "linear"] = "constant"
    inertia_end: float = Field(0.4, ge=0)
    velocity_clamp: float = Field(0.5, gt=0)
    boundary: Literal["nearest", "reflective", "random", "periodic", "intermediate", "shrink"] = "nearest"
    include_initial: bool = False


@contextlib.contextmanager
def _keep_logging():
    """pyswarms' Reporter calls logging.config.dictConfig whenever it is created (at import
    and in every handler), replacing the root handlers and disabling existing loggers;
    restore the application's logging afterwards."""
    root = logging.getLogger()
    handlers, level = list(root.handlers), root.level
    disabled = {
        name: lg.disabled
        for name, lg in logging.root.manager.loggerDict.items()
        if isinstance(lg, logging.Logger)
    }
    try:
        yield
    finally:
        root.handlers[:] = handlers
        root.setLevel(level)
        for name, lg in logging.root.manager.loggerDict.items():
            if isinstance(lg, logging.Logger):
                lg.disabled = disabled.get(name, False)


def run(evaluator, seed: int, budget: Budget, s: PSOSettings) -> Outcome:
    with _keep_logging():
        from pyswarms.backend.generators import create_swarm
        from pyswarms.backend.handlers import BoundaryHandler, VelocityHandler
        from pyswarms.backend.operators import compute_pbest
        from pyswarms.backend.topology import Star

        topology = Star()
        bh = BoundaryHandler(strategy=s.boundary)
        vh = VelocityHandler(strategy="unmodified")
    k = evaluator.n_params
    bounds = (np.zeros(k), np.ones(k))
    w0, c1, c2 = s.factor * s.inertia, s.factor * s.c1, s.factor * s.c2
    clamp = (-s.velocity_clamp, s.velocity_clamp)
    termination = Termination(budget, evaluator)
    max_iter = budget.max_iterations or max(1, budget.max_evaluations // s.swarm_size)
    with seeded_global_numpy(seed):
        swarm = create_swarm(
            n_particles=s.swarm_size,
            dimensions=k,
            options={"w": w0, "c1": c1, "c2": c2},
            bounds=bounds,
            clamp=clamp,
        )
        if s.include_initial:
            swarm.position[0] = evaluator.x_initial
        swarm.pbest_cost = np.full(s.swarm_size, np.inf)
        iteration = 0
        while termination.affords(s.swarm_size):
            if s.inertia_schedule == "linear":
                swarm.options["w"] = w0 + (s.inertia_end * s.factor - w0) * min(1.0, iteration / max_iter)
            swarm.current_cost = evaluator.objective(swarm.position)
            swarm.pbest_pos, swarm.pbest_cost = compute_pbest(swarm)
            swarm.best_pos, swarm.best_cost = topology.compute_gbest(swarm)
            iteration += 1
            # the global best so far, over successful evaluations only (= swarm.best_cost
            # without failures): a failed point's penalty never meets the target
            if termination.update(evaluator.best_objective):
                break
            swarm.velocity = topology.compute_velocity(swarm, clamp, vh, bounds)
            swarm.position = topology.compute_position(swarm, bounds, bh)
    return Outcome(
        termination.status, iteration, extra={"swarm_size": s.swarm_size, "w": w0, "c1": c1, "c2": c2}
    )


OPTIMIZER = Optimizer("pso", PSOSettings, run)
