"""MAC and COMAC of the lab frame's initial model, from the shape tables alone.

Writes the shape tables of the initial 3-DOF model against the measured modes, then reads
``mac_matrix`` back with pandas, as one would from any results folder, and prints the MAC
of each measured mode with its paired model mode.
Run: ``python examples/gallery/mac_from_tables.py [output folder]``
"""

import sys
from pathlib import Path

import pandas as pd

from framework.report.figures import draw_problem_shapes
from framework.structures.lab_frame.model import make_model, measured
from framework.updating.problem import UpdatingProblem


def main(out: Path) -> pd.DataFrame:
    problem = UpdatingProblem(make_model(), measured("base"))
    draw_problem_shapes(problem, {"initial": problem.parameters.initial}, out, structure="lab_frame_3dof")
    mac = pd.read_csv(out / "mac_matrix.csv")
    paired = mac[mac["kind"] == "measured_vs_model"].sort_values("mac").groupby("i").tail(1).sort_values("i")
    print(paired[["label_i", "f_i_hz", "label_j", "f_j_hz", "mac"]].round(4).to_string(index=False))
    return paired


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("gallery_output/mac_from_tables"))
