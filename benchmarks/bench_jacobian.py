"""Benchmark: one sensitivity-method iteration with the exact Jacobian vs finite differences.

Usage: .venv/bin/python benchmarks/bench_jacobian.py [--points 8] [--starts 3] [--budget 1000]

On the SMU footbridge (946 DOFs, 17 parameters, reference formulation with std weights;
needs ../shared/benchmarks/smu) at the same random points, measured in this one run:

- one iteration = residual vector + Jacobian: forward differences (1 + 17 eigen
  solutions, as least_squares' "2-point") against the exact Jacobian (1 eigen solution +
  modal derivatives of the 5 paired modes, Nelson's method); prints the median wall time of
  each, their ratio (target >= 5x), and the counted cost of each in eigen-solve
  equivalents (18 against 1 + 5) next to the measured time of the exact Jacobian in eigen
  solutions, which shows that the count does not understate the work;
- ``--starts`` random starts of SM with either Jacobian (evaluations as counted, wall
  time, objective); 0 skips them.

Ratios are measured in one run on one machine; nothing here is a timed test.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from framework.optimizers import Budget, run_optimizer
from framework.structures.smu import model as smu
from framework.updating.objectives import ObjectiveSpec
from framework.updating.problem import UpdatingProblem, fd_points


def _seconds(fn, *args) -> float:
    t0 = time.perf_counter()
    fn(*args)
    return time.perf_counter() - t0


def _fd_iteration(problem, x):
    """Residuals and a forward-difference Jacobian: 1 + k eigen solutions."""
    r0 = problem.evaluate(x[None, :]).residuals[0]
    X, h = fd_points(x, 1e-3)
    return (problem.evaluate(X).residuals - r0).T / h


def _exact_iteration(problem, x):
    """Residuals and the exact Jacobian at the same point: 1 eigen solution + modal derivatives."""
    ev = problem.evaluate(x[None, :], keep_results=True)
    return problem.jacobian(x, result=ev.results[0])


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=8)
    parser.add_argument("--starts", type=int, default=3)
    parser.add_argument("--budget", type=int, default=1000)
    parser.add_argument("--shape-term", choices=["mac", "eigenvector"], default="mac")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--solver", choices=["shift_invert", "shift_invert_ldl"], default="shift_invert",
                        help="eigen solver of the footbridge model (both paths use it)")
    args = parser.parse_args(argv)
    if not smu.available():
        raise SystemExit(f"SMU data not found in {smu.smu_dir()}")

    spec = ObjectiveSpec(formulation="reference",
                         options={"matching": "order", "weights": "std", "shape_term": args.shape_term})
    problem = UpdatingProblem(smu.make_footbridge(solver=args.solver), smu.footbridge_measured(), objective=spec)
    rng = np.random.default_rng(args.seed)
    points = rng.random((args.points, problem.n_params))
    problem.evaluate(points[:1])  # warm-up

    t_eigen, t_fd, t_exact, t_jac, costs = [], [], [], [], []
    for x in points:
        t_eigen.append(_seconds(problem.evaluate, x[None, :]))
        t_fd.append(_seconds(_fd_iteration, problem, x))
        t_exact.append(_seconds(_exact_iteration, problem, x))
        result = problem.evaluate(x[None, :], keep_results=True).results[0]
        t0 = time.perf_counter()
        jac = problem.jacobian(x, result=result)
        t_jac.append(time.perf_counter() - t0)
        assert jac.method == "exact", jac.reason
        costs.append(jac.cost)

    out = {
        "points": len(points),
        "eigen_median_s": statistics.median(t_eigen),
        "fd_iteration_median_s": statistics.median(t_fd),
        "exact_iteration_median_s": statistics.median(t_exact),
        "exact_jacobian_median_s": statistics.median(t_jac),
        "counted_fd": 1 + problem.n_params,
        "counted_exact": 1 + max(costs),
    }
    out["iteration_speedup"] = out["fd_iteration_median_s"] / out["exact_iteration_median_s"]
    out["jacobian_in_eigen_solutions"] = out["exact_jacobian_median_s"] / out["eigen_median_s"]
    print(f"footbridge (946 DOFs, 17 parameters, solver {args.solver}), reference formulation, shape term "
          f"{args.shape_term}, {len(points)} random points")
    print(f"one eigen solution (evaluation):      {out['eigen_median_s'] * 1e3:8.1f} ms")
    print(f"SM iteration, finite differences:     {out['fd_iteration_median_s'] * 1e3:8.1f} ms "
          f"(counted {out['counted_fd']} evaluations)")
    print(f"SM iteration, exact Jacobian:         {out['exact_iteration_median_s'] * 1e3:8.1f} ms "
          f"(counted {out['counted_exact']} = 1 + {max(costs)} eigen-solve equivalents)")
    print(f"speed-up of one iteration (fd / exact): {out['iteration_speedup']:.1f}x (target >= 5x); "
          f"counted ratio {out['counted_fd'] / out['counted_exact']:.1f}x")
    print(f"exact Jacobian alone: {out['jacobian_in_eigen_solutions']:.2f} eigen solutions measured, "
          f"{max(costs)} counted")

    if args.starts:
        budget = Budget(max_evaluations=args.budget, stall_iterations=30, stall_tolerance=1e-8, target_objective=None)
        rows = []
        for method in ("fd", "exact"):
            for seed in range(args.starts):
                r = run_optimizer("sm", problem, seed, budget, start="random", jacobian=method)
                rows.append((method, seed, r.objective, r.n_evaluations, r.n_jacobians, r.wall_s, r.status))
        print(f"\nSM from {args.starts} random starts (budget {args.budget} evaluations):")
        header = ("jacobian", "seed", "objective", "evaluations", "jacobians", "wall_s")
        print("{:>8} {:>4} {:>12} {:>11} {:>9} {:>7} status".format(*header))
        for method, seed, obj, n_ev, n_jac, wall, status in rows:
            print(f"{method:>8} {seed:>4} {obj:12.6g} {n_ev:11d} {n_jac:9d} {wall:7.2f} {status}")
        for method in ("fd", "exact"):
            sel = [r for r in rows if r[0] == method]
            out[f"sm_{method}_wall_s"] = sum(r[5] for r in sel)
            out[f"sm_{method}_evaluations"] = sum(r[3] for r in sel)
        print(f"total wall time fd / exact: {out['sm_fd_wall_s'] / out['sm_exact_wall_s']:.1f}x; "
              f"counted evaluations fd / exact: {out['sm_fd_evaluations'] / out['sm_exact_evaluations']:.1f}x")
    return out


if __name__ == "__main__":
    main()
