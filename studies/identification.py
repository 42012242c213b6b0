"""Identification study (issue 8): simulated vibration tests of the lab frame and the bridge,
FRF peak picking, N4SID / SSI-cov with stability diagrams, comparison with the true modes,
and updating of the 3-DOF lab-frame model from the identified modes.

    .venv/bin/python studies/identification.py            # full records (~20-30 s)
    .venv/bin/python studies/identification.py --quick    # shortened records
    .venv/bin/python studies/identification.py --no-bridge

Writes results/identification/ (see framework.identification.study).
"""

import os

# small dense linear algebra: one BLAS thread is much faster on a shared 2-core machine
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse  # noqa: E402
import logging  # noqa: E402

from framework.identification.study import run  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="results/identification")
    parser.add_argument("--quick", action="store_true", help="shortened records")
    parser.add_argument("--no-bridge", action="store_true", help="lab frame only")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    tables = run(args.out, bridge=not args.no_bridge, quick=args.quick)
    modes = tables["modes"]
    found = modes[modes["label"] != "spurious"]
    print(
        found.groupby(["structure", "test", "method"])[["f_error_pct", "zeta_error_pct", "mac_to_true"]]
        .agg(lambda s: s.abs().max())
        .round(4)
        .to_string()
    )
    if "updating" in tables:
        print(
            tables["updating"][["algorithm", "seed", "parameter", "true", "updated", "error_pct_of_range", "objective"]]
            .round(4)
            .to_string()
        )


if __name__ == "__main__":
    main()
