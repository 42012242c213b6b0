"""Identified modes as built-in measured data sets (for the registry and study configs).

``measured(case)`` simulates the tests with fixed seeds, identifies them and returns
:class:`~framework.measured.modes.MeasuredModes` (deterministic, ~1 s for the lab frame,
a few s for the bridge). They are the modes that ``studies/identification.yaml`` exports
to ``results/identification/*_identified.yaml`` (same tests, seeds and settings; a test
checks that they agree):

- ``"lab_frame"``: N4SID, mean of three 150 s shake-table sweeps of the true 3-DOF frame
  (``lab_tests.TRUE_THETA``), DOFs y, x, torsion;
- ``"bridge_vertical"`` / ``"bridge_lateral"``: N4SID of the 391 s vertical / lateral shaker
  sweep of the bridge model, DOFs = the uz / uy edge sensor channels.
"""

from __future__ import annotations

from framework.core.errors import InputError
from framework.identification.pipeline import IdentificationSettings
from framework.measured.modes import MeasuredModes

CASES = ("lab_frame", "bridge_vertical", "bridge_lateral")

#: identification settings of the lab-frame tests (orders 6-40, 1 %, MAC 0.9, 50 Hz after decimation)
LAB_SETTINGS = IdentificationSettings(
    orders=tuple(range(6, 41, 2)), block_rows=20, decimate=4, mac_min=0.9, band_hz=(0.5, 15.0)
)
#: identification settings of the bridge tests (orders 10-80, 1 %, MAC 0.8, 25 Hz after decimation)
BRIDGE_SETTINGS = IdentificationSettings(
    orders=tuple(range(10, 81, 2)), block_rows=30, decimate=8, mac_min=0.8, band_hz=(0.8, 10.0)
)


def measured(case: str = "lab_frame") -> MeasuredModes:
    """Identified modes of a simulated test campaign (see the module docstring)."""
    from framework.identification import pipeline as pl
    from framework.structures.bridge import vibration_tests as bridge_tests
    from framework.structures.lab_frame import vibration_tests as lab_tests

    if case == "lab_frame":
        runs = [pl.identify(lab_tests.sweep(seed), LAB_SETTINGS).selected for seed in (1, 2, 3)]
        return pl.to_measured_modes(
            pl.average_identifications(runs),
            "lab_frame_identified",
            lab_tests.MODE_LABELS,
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
