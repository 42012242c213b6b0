"""Discrepancy study (issue 9): hidden effects x noise x seeds for beam, lab frame, bridge.

    nice -n 10 .venv/bin/python studies/discrepancy.py --structures beam lab_frame --seeds 10
    nice -n 10 .venv/bin/python studies/discrepancy.py --structures bridge --seeds 4
    nice -n 10 .venv/bin/python studies/discrepancy.py --structures beam lab_frame bridge --seeds 10 --magnitudes 0.3

Writes results/discrepancy/cases.csv (one row per case), rates.csv, study.png and the
detailed tables of showcase cases (seed 1) under results/discrepancy/<case_id>/.
Resumes: stored cases are skipped (delete results/discrepancy/_cases to start over).
"""

from __future__ import annotations

import argparse
import logging

from framework.discrepancy import study


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--structures", nargs="+", default=["beam", "lab_frame"], choices=sorted(study.HIDDEN))
    p.add_argument("--seeds", type=int, default=10, help="seeds 1..N per (structure, effect, noise)")
    p.add_argument("--noise", nargs="+", default=["low", "high", "very_high"])
    p.add_argument("--magnitudes", nargs="+", type=float, default=[1.0], help="hidden-effect magnitudes")
    p.add_argument("--output", default="results/discrepancy")
    p.add_argument("--showcase-seed", type=int, default=1)
    args = p.parse_args()
    logging.basicConfig(level=logging.WARNING, format="%(message)s")
    specs = study.plan(args.structures, args.noise, range(1, args.seeds + 1), magnitudes=args.magnitudes)
    study.run(specs, args.output, showcase_seeds=[args.showcase_seed])
    cases, rates = study.consolidate(__import__("pathlib").Path(args.output))
    print(rates.to_string(index=False, float_format=lambda v: f"{v:.3g}"))


if __name__ == "__main__":
    main()
