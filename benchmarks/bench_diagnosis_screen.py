"""Benchmark: screened variants (``screen_keep``) against calibrating every location, in one run.

Usage: .venv/bin/python benchmarks/bench_diagnosis_screen.py [--seeds 1 2] [--keep 2] [--effects ...]

On the three-storey two-bay frame with ``candidates: auto`` (about 80 generated variants),
diagnoses data with a hidden effect at a random location twice: every variant calibrated
(``screen_keep`` None) and only the ``--keep`` best variants of each effect by the
linearized screen (:mod:`framework.diagnosis.screen`). Prints per case the model
evaluations of both, their ratio, and for every effect the best location of round 1 by
each path (the same location = the screen did not lose the best fit), and the named
effect and location of both.
"""

from __future__ import annotations

import argparse
import time

from framework.diagnosis.auto import with_candidates
from framework.diagnosis.generate import NOISE_LEVELS, HiddenCase, generate
from framework.diagnosis.workflow import DiagnoseSettings, diagnose
from framework.structures.frame_two_bay import effects as frame_two_bay

CASES = ("member_stiffness_change", "added_brace", "level_mass_change", "semi_rigid_connections")


def _round1(d) -> dict[str, str]:
    return {name: f.active.get(name, "") for name, f in d.rounds[0].candidate_fits.items()}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, nargs="+", default=[1])
    ap.add_argument("--keep", type=int, default=2)
    ap.add_argument("--effects", nargs="+", default=list(CASES), choices=CASES)
    args = ap.parse_args()
    cat = with_candidates(frame_two_bay.catalogue(), "auto")
    n_variants = sum(len(e.variants) for e in cat.candidate_effects().values())
    print(f"frame_two_bay: {len(cat.candidate_effects())} generated effects, {n_variants} variants")
    base = {"n_starts": 1, "max_evaluations": 50, "screen_points": 0, "refine_starts": 1, "max_rounds": 1}
    totals = {"all": 0, "screened": 0}
    same_named = same_best = n_effects = n_cases = 0
    for effect in args.effects:
        for seed in args.seeds:
            data = generate(cat, HiddenCase({effect: None}, seed=seed, noise=NOISE_LEVELS["high"]))
            out = {}
            for label, keep in (("all", None), ("screened", args.keep)):
                t0 = time.perf_counter()
                d = diagnose(cat, data, DiagnoseSettings(**base, screen_keep=keep))
                out[label] = (d, time.perf_counter() - t0)
                totals[label] += d.n_evaluations
            (da, ta), (ds, ts) = out["all"], out["screened"]
            ba, bs = _round1(da), _round1(ds)
            agree = [k for k in ba if ba[k] == bs.get(k)]
            named_a = f"{'+'.join(da.named_effects) or 'none'}[{da.after.active.get(effect, '')}]"
            named_s = f"{'+'.join(ds.named_effects) or 'none'}[{ds.after.active.get(effect, '')}]"
            n_cases += 1
            same_named += named_a == named_s
            same_best += len(agree)
            n_effects += len(ba)
            print(f"{effect}[{data.meta['hidden'][effect]}] seed {seed}: evaluations all {da.n_evaluations} "
                  f"({ta:.1f} s), screened {ds.n_evaluations} ({ts:.1f} s), ratio "
                  f"{da.n_evaluations / ds.n_evaluations:.1f}; best location per effect equal for "
                  f"{len(agree)}/{len(ba)}; named: all {named_a}, screened {named_s}")  # fmt: skip
    print(f"total evaluations: all {totals['all']}, screened {totals['screened']}, ratio "
          f"{totals['all'] / totals['screened']:.1f}; same named effect and location in {same_named}/{n_cases} "
          f"cases; same best location per effect in {same_best}/{n_effects}")  # fmt: skip


if __name__ == "__main__":
    main()
