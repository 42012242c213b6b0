"""Write my_modes.yaml: the modes of my_frame with a first-storey infill wall that the model
lacks (an added diagonal strut from node 1 to node 12 of axial stiffness 0.8 k_ref, the
generated candidate added_brace[n1-n12]) plus 0.3 % / 2 % noise.

    python make_modes.py        (in examples/diagnosis)
"""

import my_frame
import numpy as np
import yaml

from framework.diagnosis.auto import catalogue_of_model, with_auto

cat = with_auto(catalogue_of_model(my_frame.model(), "my_frame", 4))
truth = cat.model({"added_brace": "n1-n12"}).modal(
    {"column_stiffness_ratio": 1.03, "beam_stiffness_ratio": 0.97, "brace_stiffness_ratio": 0.8})
rng = np.random.default_rng(7)
modes = []
for j in range(4):
    phi = truth.shapes[:, j] / truth.shapes[np.argmax(np.abs(truth.shapes[:, j])), j]
    f = float(truth.frequencies_hz[j] * (1 + 0.003 * rng.standard_normal()))
    modes.append({"label": f"mode {j + 1}", "frequency_hz": f, "frequency_std_hz": 0.003 * f,
                  "shape": [float(v) for v in phi + 0.02 * rng.standard_normal(phi.size)],
                  "shape_std": [0.02] * phi.size})
with open("my_modes.yaml", "w") as fh:
    yaml.safe_dump({"name": "my_frame_test", "dofs": list(truth.dofs), "modes": modes}, fh, sort_keys=False)
