"""Lab frame 3-DOF: 50 000 points evaluated in one call, against the per-point paths; then
evaluations per second one point at a time vs the whole swarm at once, and the speed-up of 2
worker processes over 1. Ratios are measured in one run (never asserted: machines are shared).

The 50 000-point call (``UpdatingProblem.evaluate`` on a (50000, 6) array) runs on the array
path: one batched eigh, batched MAC and pairing, no per-point Python object. It is compared with
(a) the same call through a runner that returns one ModalResult per point (the path of every
runner that is not in-process, and the only path before the array path existed) and (b) one
point at a time (``objective1`` in a loop, timed on 2 000 of the points and scaled). The array
path is also timed in CPU seconds of this process: on a loaded, shared machine the wall time
includes waiting for a core.

Run:  .venv/bin/python benchmarks/bench_lab_frame.py
"""

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from framework.structures.lab_frame.model import make_model, measured  # noqa: E402
from framework.study.bench import main  # noqa: E402
from framework.updating.problem import UpdatingProblem  # noqa: E402

N_POINTS = 50_000
N_SINGLE = 2_000


def _best_time(fn, repeats: int) -> float:
    best = np.inf
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def _best_cpu_time(fn, repeats: int) -> float:
    """CPU seconds of this process (single-threaded BLAS): the cost on a loaded, shared machine."""
    best = np.inf
    for _ in range(repeats):
        t = time.process_time()
        fn()
        best = min(best, time.process_time() - t)
    return best


def _per_point_runner(model, thetas):
    """A runner that hands back one ModalResult per point (as process and Dask runners do)."""
    return model.modal_batch(thetas)


def array_path(repeats: int = 3) -> dict:
    """Seconds for N_POINTS points in one call on the array path and on the per-point paths."""
    problem = UpdatingProblem(make_model(), measured())
    X = np.random.default_rng(0).random((N_POINTS, problem.n_params))
    fast = problem.evaluate(X)
    listed = problem.evaluate(X, _per_point_runner)
    single = np.array([problem.objective1(x) for x in X[:200]])
    # the paths agree (the tests check 1e-12; here a sanity check of the timed numbers)
    assert np.allclose(fast.objective, listed.objective, rtol=1e-12, atol=0)
    assert np.allclose(fast.objective[:200], single, rtol=1e-12, atol=0)
    t_array = _best_time(lambda: problem.evaluate(X), repeats)
    cpu_array = _best_cpu_time(lambda: problem.evaluate(X), repeats)
    t_list = _best_time(lambda: problem.evaluate(X, _per_point_runner), repeats)
    t_single = _best_time(lambda: [problem.objective1(x) for x in X[:N_SINGLE]], 1) * N_POINTS / N_SINGLE
    return {"points": N_POINTS, "array_s": t_array, "array_cpu_s": cpu_array, "per_point_objects_s": t_list,
            "one_at_a_time_s": t_single}


if __name__ == "__main__":
    r = array_path()
    sys.stdout.write(
        f"lab_frame_3dof: {r['points']} points in one call {r['array_s']:.3f} s wall, {r['array_cpu_s']:.3f} s CPU "
        f"(array path, best of 3; target < 0.3 s); "
        f"per-point objects {r['per_point_objects_s']:.3f} s, ratio {r['per_point_objects_s'] / r['array_s']:.1f}; "
        f"one point at a time {r['one_at_a_time_s']:.1f} s (from {N_SINGLE} points), "
        f"ratio {r['one_at_a_time_s'] / r['array_s']:.0f}\n"
    )
    sys.stdout.flush()
    raise SystemExit(main(["lab_frame_3dof"], workers=2, repeats=3))
