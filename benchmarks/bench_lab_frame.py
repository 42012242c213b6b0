"""Lab frame 3-DOF: evaluations per second one point at a time vs the whole swarm at once
(vectorized), and the speed-up of 2 worker processes over 1. Ratios are measured in one run.

Run:  .venv/bin/python benchmarks/bench_lab_frame.py      (same as `gomu bench lab_frame_3dof`)
"""

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from framework.bench import main  # noqa: E402

if __name__ == "__main__":
    raise SystemExit(main(["lab_frame_3dof"], workers=2, repeats=3))
