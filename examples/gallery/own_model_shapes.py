"""Mode shapes and MAC of your own OpenSees model against measured modes.

Takes the two-storey model of ``examples/own_model.py``, makes 'measured' modes from a
stiffer first storey, and writes the shape tables and figures (model modes on the geometry,
measured over model before and after updating, MAC heatmaps, COMAC) to an output folder.
Run: ``python examples/gallery/own_model_shapes.py [output folder]``
"""

import runpy
import sys
from pathlib import Path

from framework.measured.modes import MeasuredModes
from framework.report.figures import draw_problem_shapes
from framework.updating.problem import UpdatingProblem

HERE = Path(__file__).resolve().parent


def main(out: Path) -> list[Path]:
    example = runpy.run_path(str(HERE.parent / "own_model.py"))  # model, params
    model, params = example["model"], example["params"]
    truth = model.modal({"k1_n_per_m": 2.6e6, "k2_n_per_m": 1.2e6})  # stands in for a test
    data = MeasuredModes(truth.frequencies_hz, ("floor1", "floor2"), truth.shapes, labels=("1st", "2nd"))
    problem = UpdatingProblem(model, data)
    states = {"initial": params.initial, "updated": [2.6e6, 1.2e6]}
    files = draw_problem_shapes(problem, states, out)
    for f in files:
        print(f)
    return files


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("gallery_output/own_model_shapes"))
