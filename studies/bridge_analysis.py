"""Bridge study parts that are not optimizer runs, plus the summary of those runs.

Usage (after ``gomu run studies/bridge.yaml``, which writes results/bridge/updating/):

    .venv/bin/python studies/bridge_analysis.py [--skip initial,sensitivity,cables,summary]

Writes tables (CSV) and figures (PNG) to results/bridge/.
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

from framework.models import bridge_study

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "results" / "bridge"


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--skip", default="", help="comma-separated parts to skip")
    args = parser.parse_args(argv)
    skip = set(filter(None, args.skip.split(",")))
    logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    OUT.mkdir(parents=True, exist_ok=True)
    bridge_study.write_notes(OUT)
    if "initial" not in skip:
        df = bridge_study.initial_frequencies(OUT)
        print(df.pivot_table(index=["mode", "label"], columns="cable_elements", values="f_model_hz").round(3))
    if "sensitivity" not in skip:
        table = bridge_study.sensitivities(OUT)
        print(table.pivot_table(index=["quantity", "mode"], columns="parameter", values="sensitivity").round(3))
    if "cables" not in skip:
        df = bridge_study.cable_models(OUT)
        print(df[["cable_elements", "stage", "mode", "f_measured_hz", "f_model_hz", "error_pct", "mac", "matched"]])
    if "summary" not in skip and (OUT / "updating" / "runs.csv").exists():
        for name, frame in bridge_study.summarize_updating(OUT / "updating", OUT).items():
            print(f"--- {name}")
            print(frame.round(4).to_string())


if __name__ == "__main__":
    main()
