"""Benchmark: repeated eigen solutions of the footbridge, reused LDL' against today's shift-invert.

Usage: .venv/bin/python benchmarks/bench_repeated_eigen.py [--points 200] [--rounds 3]

On the SMU footbridge (946 DOFs, 17 parameters, 5 modes; needs ../shared/benchmarks/smu or
$GOMU_SMU_DIR) at the same random points in the box, in this one process:

- today's path: ``MatrixModel(solver="shift_invert")``, scipy ``eigsh`` in shift-invert mode
  (SuperLU factorization from scratch per point, 20 Lanczos vectors);
- the reused path: ``solver="shift_invert_ldl"`` (:mod:`framework.models.repeated_eigen`:
  QDLDL numeric refactorization on a symbolic analysis done once, 15 Lanczos vectors);

timed in alternating rounds (CPU time of this process, single-threaded BLAS), each round
over all points; prints the median per-solve time of each path, their ratio (target >= 2x)
and the accuracy of the reused path against today's: the largest relative frequency
difference, the largest 1 - MAC of the full shapes and the largest difference of the shapes
at the 58 measured DOFs relative to their largest entry. Also the one-off cost of the
symbolic analysis. Nothing here is a timed test.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from framework.models import repeated_eigen
from framework.structures.smu import model as smu


def _solve_all(model, thetas) -> tuple[float, list]:
    t0 = time.process_time()
    out = [model.eigen(t) for t in thetas]
    return (time.process_time() - t0) / len(thetas), out


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=200)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    if not smu.available():
        raise SystemExit(f"SMU data not found in {smu.smu_dir()}")
    if not repeated_eigen.available():
        raise SystemExit("the reused path needs the optional package qdldl (pip install gomu[fast])")

    today = smu.make_footbridge(solver="shift_invert")
    reused = smu.make_footbridge(solver="shift_invert_ldl")
    params = today.parameters
    rng = np.random.default_rng(args.seed)
    X = rng.random((args.points, len(params)))
    thetas = [dict(zip(params.names, params.to_physical(x))) for x in X]
    t0 = time.process_time()
    reused._reused_ldl()
    t_symbolic = time.process_time() - t0
    # only points where today's path succeeds (a K that is not positive definite fails on both)
    ok = []
    for t in thetas:
        try:
            today.eigen(t)
            ok.append(t)
        except Exception:  # noqa: BLE001 - failed points are left out of both timings
            pass
    t_today, t_reused = [], []
    for _ in range(args.rounds):
        a, ref = _solve_all(today, ok)
        b, new = _solve_all(reused, ok)
        t_today.append(a)
        t_reused.append(b)
    mass = today.mass
    d_freq, d_mac, d_shape = 0.0, 0.0, 0.0
    for (lam0, phi0), (lam1, phi1) in zip(ref, new):
        d_freq = max(d_freq, float(np.max(np.abs(np.sqrt(lam1 / lam0) - 1.0))))
        cross = np.einsum("ij,ij->j", phi0, mass @ phi1)
        mac = cross**2 / (np.einsum("ij,ij->j", phi0, mass @ phi0) * np.einsum("ij,ij->j", phi1, mass @ phi1))
        d_mac = max(d_mac, float(np.max(1.0 - mac)))
        m0, m1 = phi0[today.dof_index], phi1[today.dof_index] * np.sign(cross)
        d_shape = max(d_shape, float(np.max(np.abs(m1 - m0) / np.max(np.abs(m0), axis=0))))
    out = {
        "points": len(ok), "failed_points": len(thetas) - len(ok), "rounds": args.rounds,
        "today_ms": 1e3 * statistics.median(t_today), "reused_ms": 1e3 * statistics.median(t_reused),
        "symbolic_ms": 1e3 * t_symbolic, "max_rel_frequency_difference": d_freq,
        "max_one_minus_mac": d_mac, "max_rel_shape_difference": d_shape,
    }
    out["speedup"] = out["today_ms"] / out["reused_ms"]
    print(f"footbridge (946 DOFs, 5 modes), {len(ok)} random points ({out['failed_points']} not positive "
          f"definite, left out), {args.rounds} alternating rounds, CPU time per solve (median of rounds)")
    print(f"today's shift-invert (SuperLU from scratch): {out['today_ms']:7.2f} ms  rounds "
          + " ".join(f"{1e3 * t:.2f}" for t in t_today))
    print(f"reused LDL' + shift-invert Lanczos:          {out['reused_ms']:7.2f} ms  rounds "
          + " ".join(f"{1e3 * t:.2f}" for t in t_reused))
    print(f"speed-up today / reused: {out['speedup']:.2f}x (target >= 2x); one-off symbolic analysis "
          f"{out['symbolic_ms']:.1f} ms")
    print(f"accuracy vs today: max |f/f_today - 1| {d_freq:.2e}, max 1 - MAC (full shapes) {d_mac:.2e}, "
          f"max shape difference at measured DOFs {d_shape:.2e} (relative to the mode's largest entry)")
    return out


if __name__ == "__main__":
    main()
