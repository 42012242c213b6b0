"""Identified modes as built-in measured data sets (for the registry and study configs).

``measured(case)`` simulates the tests with fixed seeds, identifies them and returns
:class:`~framework.measurements.MeasuredModes` (deterministic, ~1 s for the lab frame,
a few s for the bridge):

- ``"lab_frame"``: N4SID, mean of three 150 s shake-table sweeps of the true 3-DOF frame
  (``lab_tests.TRUE_THETA``), DOFs y, x, torsion;
- ``"bridge_vertical"`` / ``"bridge_lateral"``: N4SID of the 391 s vertical / lateral shaker
  sweep of the bridge model, DOFs = the uz / uy edge sensor channels.
"""

from __future__ import annotations

from framework.errors import InputError
from framework.measurements import MeasuredModes

CASES = ("lab_frame", "bridge_vertical", "bridge_lateral")


def measured(case: str = "lab_frame") -> MeasuredModes:
    """Identified modes of a simulated test campaign (see the module docstring)."""
    from framework.identification import bridge_tests, lab_tests
    from framework.identification import pipeline as pl
    from framework.identification.study import BRIDGE_SETTINGS, LAB_LABELS, LAB_SETTINGS

    if case == "lab_frame":
        runs = [pl.identify(lab_tests.sweep(seed), LAB_SETTINGS).selected for seed in (1, 2, 3)]
        return pl.to_measured_modes(
            pl.average_identifications(runs),
            "lab_frame_identified",
            LAB_LABELS,
            source="N4SID, mean of 3 simulated shake-table sweeps",
        )
    if case in ("bridge_vertical", "bridge_lateral"):
        direction = case.split("_", 1)[1]
        comp = "uz" if direction == "vertical" else "uy"
        full = bridge_tests.sweep(1 if direction == "vertical" else 2, direction)
        rec = full.select([c for c in full.output_labels if c.endswith(comp)])
        ident = pl.identify(rec, BRIDGE_SETTINGS)
        return pl.to_measured_modes(
            ident.selected, f"bridge_{direction}_identified", source=f"N4SID of a simulated {direction} shaker sweep"
        )
    raise InputError(f"identified measured data: unknown case {case!r}; known: {list(CASES)}")
