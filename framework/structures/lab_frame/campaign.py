"""The lab frame's simulated test campaign and the modes identified from it.

:data:`CAMPAIGN` (the ``identification`` kind's tests of structure ``lab_frame``):
``sweep`` (shake table, 0-15 Hz, 150 s, input-output) and ``snap_back`` (free decay,
40 s, output only) on the true 3-DOF frame (:mod:`.vibration_tests`).

:func:`identified` is the built-in data set ``measured: {builtin: identified, case:
lab_frame}``: N4SID, mean of three 150 s shake-table sweeps of the true frame
(``vibration_tests.TRUE_THETA``), DOFs y, x, torsion (deterministic, about 1 s). They are
the modes that ``studies/identification.yaml`` exports to
``results/identification/lab_frame_identified.yaml`` (same tests, seeds and settings; a
test checks that they agree).
"""

from __future__ import annotations

from framework.identification.campaign import Campaign, SimulatedTest, TrueModes
from framework.identification.pipeline import IdentificationSettings
from framework.identification.records import VibrationRecord
from framework.measured.modes import MeasuredModes
from framework.structures.lab_frame import model as lf
from framework.structures.lab_frame import vibration_tests as lab_tests

TESTS = {
    "sweep": SimulatedTest(True, 150.0, (0.0, 15.0)),
    "snap_back": SimulatedTest(False, 40.0, free_decay=True),
}

#: identification settings of the lab-frame tests (orders 6-40, 1 %, MAC 0.9, 50 Hz after decimation)
SETTINGS = IdentificationSettings(
    orders=tuple(range(6, 41, 2)), block_rows=20, decimate=4, mac_min=0.9, band_hz=(0.5, 15.0)
)


def record(test: str, seed: int, *, duration_s: float, sampling_hz: float, output_noise: float,
           input_noise: float | None, f_range_hz) -> VibrationRecord:
    """One record of ``test`` (channels y, x, torsion)."""
    common = {"duration_s": duration_s, "output_noise": output_noise, "sampling_hz": sampling_hz}
    if test == "sweep":
        return lab_tests.sweep(seed, f_range_hz=f_range_hz, input_noise=input_noise, **common)
    return lab_tests.snap_back(seed, **common)


def truth() -> TrueModes:
    """The three modes of the true frame at the channels y, x, torsion."""
    f, zeta, shapes = lab_tests.true_modes()
    return TrueModes(f, zeta, shapes, tuple(lab_tests.MODE_LABELS), channels=tuple(lf.DOFS))


CAMPAIGN = Campaign("lab_frame", TESTS, record, truth)


def identified() -> MeasuredModes:
    """Identified modes of three simulated shake-table sweeps (module docstring)."""
    from framework.identification import pipeline as pl

    runs = [pl.identify(lab_tests.sweep(seed), SETTINGS).selected for seed in (1, 2, 3)]
    return pl.to_measured_modes(
        pl.average_identifications(runs),
        "lab_frame_identified",
        lab_tests.MODE_LABELS,
        source="N4SID, mean of 3 simulated shake-table sweeps",
    )
