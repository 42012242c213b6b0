"""Write model modes to a Universal File (dataset 55) and read them back as measured modes.

The 3-DOF lab frame's modes are written with a mapping file from test DOFs (node + axis)
to model DOFs, read back through the same mapping, and compared (pyuff writes E13.5, so
frequencies and shapes agree to about 6 significant digits).
Run: ``python examples/gallery/uff_round_trip.py [output folder]``
"""

import sys
from pathlib import Path

import numpy as np

from framework.core.correlation import mac_paired
from framework.measured.load import read_uff_modes, write_uff_modes
from framework.measured.modes import MeasuredModes
from framework.structures.lab_frame.model import make_model

MAPPING = """\
dofs:
  "1+y": y
  "1+x": x
  "2+y": torsion
"""


def main(out: Path) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    mapping = out / "mapping.yaml"
    mapping.write_text(MAPPING)
    r = make_model().modal({})
    modes = MeasuredModes(r.frequencies_hz, r.dofs, r.shapes, labels=("1st y", "1st x", "1st torsion"))
    path = write_uff_modes(out / "lab_frame_modes.unv", modes, mapping=mapping)
    back = read_uff_modes(path, mapping)
    f_err = np.max(np.abs(back.frequencies_hz / modes.frequencies_hz - 1))
    mac = mac_paired(back.shapes, modes.shapes)
    print(f"{path}: {back.n_modes} modes, largest relative frequency difference {f_err:.1e}, MAC {mac.round(9)}")
    return {"f_err": f_err, "mac": mac}


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("gallery_output/uff_round_trip"))
