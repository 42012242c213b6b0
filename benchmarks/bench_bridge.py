"""Benchmark: plain OpenSees path vs fast path of the bridge model, in one run.

Usage: .venv/bin/python benchmarks/bench_bridge.py [--points 15] [--cable-elements 4]

Evaluates the same random points of the parameter box (ratios 0.6-1.3) with both paths,
prints the median wall time per evaluation of each path, their ratio, and the largest
differences of paired frequencies and MACs (modes paired with the measured reference by
MAC, as the updating problem does).
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from framework.core.correlation import pair_modes
from framework.structures import bridge


def _paired(result, measured):
    p = pair_modes(
        result.frequencies_hz,
        measured.frequencies_hz,
        result.at(measured.dofs),
        measured.shapes,
        frequency_window=0.35,
    )
    return p.analytical_index, result.frequencies_hz[p.analytical_index], p.mac


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=15)
    parser.add_argument("--cable-elements", type=int, default=4)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)

    fast = bridge.make_model(args.cable_elements, fast=True)
    plain = fast.plain
    measured = bridge.measured()
    t0 = time.perf_counter()
    fast.operators  # noqa: B018 - one-off extraction, reported separately
    t_extract = time.perf_counter() - t0
    rng = np.random.default_rng(args.seed)
    points = [{}] + [dict(zip(bridge.PARAMETER_NAMES, rng.uniform(0.6, 1.3, 6))) for _ in range(args.points - 1)]
    fast.modal({}), plain.modal({})  # warm-up
    t_fast, t_plain, df, dmac = [], [], [], []
    for theta in points:
        t0 = time.perf_counter()
        rf = fast.modal(theta)
        t_fast.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        rp = plain.modal(theta)
        t_plain.append(time.perf_counter() - t0)
        i_f, f_f, m_f = _paired(rf, measured)
        i_p, f_p, m_p = _paired(rp, measured)
        same = (i_f >= 0) & (i_p >= 0)
        df.append(float(np.max(np.abs(f_f[same] / f_p[same] - 1.0))))
        dmac.append(float(np.max(np.abs(m_f - m_p))))
    out = {
        "points": len(points),
        "plain_median_s": statistics.median(t_plain),
        "fast_median_s": statistics.median(t_fast),
        "extraction_s": t_extract,
        "max_rel_freq_diff": max(df),
        "max_mac_diff": max(dmac),
    }
    out["speedup"] = out["plain_median_s"] / out["fast_median_s"]
    print(f"bridge model, {args.cable_elements} elements per cable, {len(points)} points")
    print(f"plain path median: {out['plain_median_s'] * 1e3:8.1f} ms per evaluation")
    print(
        f"fast path median:  {out['fast_median_s'] * 1e3:8.1f} ms per evaluation "
        f"(+ {t_extract:.2f} s one-off extraction)"
    )
    print(f"speed-up (plain / fast): {out['speedup']:.1f}x")
    print(f"max relative difference of paired frequencies: {out['max_rel_freq_diff']:.2e}")
    print(f"max difference of paired MACs: {out['max_mac_diff']:.2e}")
    return out


if __name__ == "__main__":
    main()
