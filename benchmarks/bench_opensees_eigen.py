"""Benchmark: OpenSeesModel's eigen solvers per evaluation, old vs new (solver="scipy"), in one run.

Usage: .venv/bin/python benchmarks/bench_opensees_eigen.py [--points 20] [--seed 0] [--bridge]

For the detailed lab frame (old default: OpenSees' -genBandArpack; also -fullGenLapack, the
deterministic OpenSees solver; and "scipy+linear", the new solver with the six bracket springs
declared as linear_parameters) and the beam's OpenSees backend (old: -fullGenLapack; also
"scipy+linear" with its element stiffness ratios declared linear), and with
--bridge the bridge's plain path (old: OpenSees' default ARPACK), evaluates the same random
points of the parameter box with every solver, interleaved, and prints the median wall time
per evaluation (build, analysis and eigen solution included), the ratio to the new solver,
the largest relative frequency difference and 1 - MAC to the new solver's modes, and the
number of failed evaluations (OpenSees' -fullGenLapack reports complex or negative eigenvalues
for the detailed lab frame at some points of its parameter box).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import statistics
import time

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

from framework.core.errors import ModelEvaluationError  # noqa: E402


def _structures(bridge: bool) -> dict:
    from framework.structures.beam import model as beam
    from framework.structures.lab_frame import detailed as lab_frame_detailed

    lab = lab_frame_detailed.make_model()
    beam_model = beam.make_opensees_model()
    out = {
        "lab_frame_detailed": (lab, ("-genBandArpack", "-fullGenLapack"), tuple(lab.parameters.names)),
        "beam_opensees": (beam_model, ("-fullGenLapack",), tuple(beam_model.parameters.names)),
    }
    if bridge:
        from framework.structures.bridge import make_model

        out["bridge_plain"] = (make_model(fast=False), ("",), ())
    return out


def _mac_diagonal(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return (np.sum(a * b, axis=0) ** 2) / (np.sum(a * a, axis=0) * np.sum(b * b, axis=0))


def bench(model, old_solvers, n_points: int, seed: int, linear: tuple[str, ...] = ()) -> list[dict]:
    """Median ms per evaluation of each solver on the same points, and differences to 'scipy'.

    With ``linear`` also "scipy+linear": solver 'scipy' with these linear_parameters (operators
    extracted during the warm-up, reported separately as setup_ms).
    """
    models = {s: dataclasses.replace(model, solver=s) for s in ("scipy", *old_solvers)}
    if linear:
        models["scipy+linear"] = dataclasses.replace(model, solver="scipy", linear_parameters=linear)
        old_solvers = ("scipy+linear", *old_solvers)
    rng = np.random.default_rng(seed)
    lower = np.array([p.lower for p in model.parameters])
    upper = np.array([p.upper for p in model.parameters])
    points = [{}] + [dict(zip(model.parameters.names, rng.uniform(lower, upper))) for _ in range(n_points - 1)]
    setup = {}
    for s, m in models.items():
        t0 = time.perf_counter()
        m.modal({})  # warm-up (and the extraction of the linear operators)
        setup[s] = time.perf_counter() - t0
    times = {s: [] for s in models}
    failed = {s: 0 for s in models}
    df = {s: 0.0 for s in old_solvers}
    dmac = {s: 0.0 for s in old_solvers}
    for theta in points:
        results = {}
        for s, m in models.items():
            t0 = time.perf_counter()
            try:
                results[s] = m.modal(theta)
            except ModelEvaluationError:
                failed[s] += 1
            times[s].append(time.perf_counter() - t0)
        new = results.get("scipy")
        for s in old_solvers:
            old = results.get(s)
            if old is None or new is None:
                continue
            if old.n_modes != new.n_modes:
                df[s] = dmac[s] = float("nan")
                continue
            df[s] = max(df[s], float(np.max(np.abs(old.frequencies_hz / new.frequencies_hz - 1.0))))
            dmac[s] = max(dmac[s], float(np.max(1.0 - _mac_diagonal(old.shapes, new.shapes))))
    t_new = statistics.median(times["scipy"])
    rows = [{"solver": "scipy", "ms": 1e3 * t_new, "ratio": 1.0, "df": 0.0, "dmac": 0.0, "failed": failed["scipy"]}]
    for s in old_solvers:
        t = statistics.median(times[s])
        rows.append({"solver": s or "(OpenSees default)", "ms": 1e3 * t, "ratio": t / t_new, "df": df[s],
                     "dmac": dmac[s], "failed": failed[s], "setup_ms": 1e3 * setup[s]})
    return rows


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=20)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--bridge", action="store_true", help="also the bridge's plain path (~0.5 s per evaluation)")
    args = parser.parse_args(argv)
    out = {}
    for name, (model, old, linear) in _structures(args.bridge).items():
        rows = bench(model, old, args.points, args.seed, linear)
        out[name] = rows
        print(f"{name} ({args.points} points, median per evaluation)")
        for r in rows:
            print(f"  {r['solver']:<20s} {r['ms']:8.2f} ms  x{r['ratio']:5.2f} of scipy   "
                  f"max |df/f| {r['df']:.1e}   max 1-MAC {r['dmac']:.1e}   failed {r['failed']}"
                  + (f"   (operators {r['setup_ms']:.0f} ms once)" if r["solver"] == "scipy+linear" else ""))
    return out


if __name__ == "__main__":
    main()
