"""Published modal data of the footbridge (SPEC section 6): measured and design-model values.

Frequencies in Hz, damping as ratios of critical. Measured mode shapes are not published
(see :mod:`framework.structures.bridge.reference` for the reference shapes).
"""

from __future__ import annotations

#: measured modes (subspace identification), SPEC section 6
MEASURED_HZ = (1.64, 1.90, 3.69, 4.86, 5.33, 6.31, 7.42, 8.32)
MEASURED_PEAK_HZ = (1.64, 1.90, 3.66, 4.85, 5.36, 6.32, 7.42, 8.33)
MEASURED_DAMPING = (0.0022, 0.0087, 0.0052, 0.0081, 0.0061, 0.0049, 0.0096, 0.0143)
MEASURED_LABELS = (
    "1st vertical",
    "2nd vertical (cable-coupled)",
    "3rd vertical",
    "1st horizontal",
    "2nd horizontal",
    "4th vertical",
    "5th vertical",
    "1st torsional",
)
MEASURED_TYPES = ("vertical", "vertical", "vertical", "lateral", "lateral", "vertical", "vertical", "torsional")
#: the source's initial (design) model, another FE package
DESIGN_MODEL_HZ = (1.66, 1.88, 3.88, 5.28, 5.45, 6.79, 7.76, 8.66)
