"""Benchmarks printed as ratios measured in one run (never asserted: machines are shared).

For each structure:
- evaluations per second evaluating one point at a time (``objective1`` in a loop) and a
  whole swarm at once (``objective(X)``; vectorized where the model has ``modal_batch``),
  and their ratio;
- the speed-up of 2 worker processes over 1 for a population (``ProcessRunner``) and for
  whole optimizer runs (the study runner's process backend).
"""

from __future__ import annotations

import sys
import time

import numpy as np

from framework.structures.registry import builtin_measured, make_structure
from framework.updating.problem import UpdatingProblem

#: structure -> measured data set used for the benchmark
DATA = {"lab_frame_3dof": "lab_frame", "lab_frame_detailed": "lab_frame", "bridge": "bridge", "beam": "beam"}


def _problem(structure: str) -> UpdatingProblem:
    model = make_structure(structure)
    return UpdatingProblem(model, builtin_measured(DATA.get(structure, structure)))


def _rate(fn, n: int, repeats: int) -> float:
    best = np.inf
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return n / best


def evaluation_rates(structure: str, n_points: int, repeats: int = 3) -> dict:
    """Evaluations per second, one at a time vs the whole population in one call."""
    problem = _problem(structure)
    X = np.random.default_rng(0).random((n_points, problem.n_params))
    single = _rate(lambda: [problem.objective1(x) for x in X], n_points, repeats)
    batch = _rate(lambda: problem.objective(X), n_points, repeats)
    return {"structure": structure, "points": n_points, "single_eval_per_s": single,
            "batch_eval_per_s": batch, "batch_over_single": batch / single}


def population_speedup(structure: str, n_points: int, workers: int = 2, repeats: int = 2) -> dict:
    """Population of n points in one call: one process vs ``workers`` processes (ProcessRunner)."""
    from framework.execution.parallel import ProcessRunner

    problem = _problem(structure)
    X = np.random.default_rng(1).random((n_points, problem.n_params))
    one = _rate(lambda: problem.objective(X), n_points, repeats)
    runner = ProcessRunner(workers)
    try:
        problem.objective(X[:workers], runner)  # start the pool outside the timing
        many = _rate(lambda: problem.objective(X, runner), n_points, repeats)
    finally:
        runner.close()
    return {"structure": structure, "points": n_points, "workers": workers, "serial_eval_per_s": one,
            "parallel_eval_per_s": many, "speedup": many / one}


def run_speedup(structure: str, runs: int = 4, workers: int = 2, max_evaluations: int = 2000) -> dict:
    """Whole PSO runs: serial vs ``workers`` processes (the study runner's process backend)."""
    from framework.execution.parallel import map_unordered
    from framework.study.config import validate
    from framework.study.execute import execute_run
    from framework.study.plan import plan

    cfg = validate({
        "study": "bench", "structure": {"name": structure},
        "measured": {"builtin": DATA.get(structure, structure)},
        "budget": {"max_evaluations": max_evaluations, "target_objective": None, "stall_iterations": 10**6},
        "algorithms": {"pso": {"algorithm": "pso"}}, "runs": runs, "execution": {"progress": False},
    })
    specs = plan(cfg)
    timings = {}
    for backend, w in (("serial", 1), ("processes", workers)):
        t = time.perf_counter()
        for _ in map_unordered(execute_run, specs, backend=backend, workers=w):
            pass
        timings[backend] = time.perf_counter() - t
    return {"structure": structure, "runs": runs, "evaluations_per_run": max_evaluations,
            "serial_s": timings["serial"], "parallel_s": timings["processes"], "workers": workers,
            "speedup": timings["serial"] / timings["processes"]}


def main(structures: list[str], workers: int = 2, repeats: int = 3) -> int:
    out = sys.stdout
    out.write("# gomu bench: ratios are measured within this one run\n")
    for s in structures:
        n = 200 if s == "lab_frame_3dof" else 40
        r = evaluation_rates(s, n, repeats)
        out.write(f"{s}: one at a time {r['single_eval_per_s']:.0f} eval/s, whole population "
                  f"{r['batch_eval_per_s']:.0f} eval/s, ratio {r['batch_over_single']:.2f}\n")
        p = population_speedup(s, n, workers, max(1, repeats - 1))
        out.write(f"{s}: population of {n} on {workers} processes {p['parallel_eval_per_s']:.0f} eval/s vs "
                  f"serial {p['serial_eval_per_s']:.0f} eval/s, speed-up {p['speedup']:.2f}\n")
        evals = 4000 if s == "lab_frame_3dof" else 300
        q = run_speedup(s, runs=2 * workers, workers=workers, max_evaluations=evals)
        out.write(f"{s}: {q['runs']} PSO runs of {evals} evaluations, serial {q['serial_s']:.2f} s, "
                  f"{workers} processes {q['parallel_s']:.2f} s, speed-up {q['speedup']:.2f}\n")
        out.flush()
    return 0
