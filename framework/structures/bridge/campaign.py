"""The bridge's simulated test campaign and the modes identified from it.

:data:`CAMPAIGN` (the ``identification`` kind's tests of structure ``bridge``):
``sweep_vertical`` / ``sweep_lateral`` (three shakers, 1-15 Hz, 391 s; uz / uy channels)
and ``jumping`` (300 s, output only; uz channels) on the bridge model of
:mod:`.vibration_tests`. A component's channels see the modes of its types (uz: vertical
and torsional, uy: lateral and torsional).

:func:`identified` gives the built-in data sets ``measured: {builtin: identified, case:
bridge_vertical | bridge_lateral}``: N4SID of the 391 s vertical / lateral shaker sweep,
DOFs = the uz / uy edge sensor channels (deterministic, a few s). They are the modes that
``studies/identification.yaml`` exports to ``results/identification/`` (same tests, seeds
and settings).
"""

from __future__ import annotations

from framework.core.errors import InputError
from framework.identification.campaign import Campaign, SimulatedTest, TrueModes
from framework.identification.pipeline import IdentificationSettings
from framework.identification.records import VibrationRecord
from framework.measured.modes import MeasuredModes
from framework.structures.bridge import vibration_tests as bridge_tests

TESTS = {
    "sweep_vertical": SimulatedTest(True, bridge_tests.SWEEP_DURATION_S, bridge_tests.SWEEP_RANGE_HZ,
                                    component="uz"),
    "sweep_lateral": SimulatedTest(True, bridge_tests.SWEEP_DURATION_S, bridge_tests.SWEEP_RANGE_HZ,
                                   component="uy"),
    "jumping": SimulatedTest(False, 300.0, component="uz"),
}
#: components the channels can be restricted to, with the mode types their channels see
COMPONENTS = {"all": None, **bridge_tests.COMPONENT_MODE_TYPES}

#: identification settings of the bridge tests (orders 10-80, 1 %, MAC 0.8, 25 Hz after decimation)
SETTINGS = IdentificationSettings(
    orders=tuple(range(10, 81, 2)), block_rows=30, decimate=8, mac_min=0.8, band_hz=(0.8, 10.0)
)
IDENTIFIED_CASES = ("bridge_vertical", "bridge_lateral")


def record(test: str, seed: int, *, duration_s: float, sampling_hz: float, output_noise: float,
           input_noise: float | None, f_range_hz) -> VibrationRecord:
    """One record of ``test`` (every sensor channel)."""
    common = {"duration_s": duration_s, "output_noise": output_noise, "sampling_hz": sampling_hz}
    if test == "jumping":
        return bridge_tests.jumping(seed, **common)
    direction = test.removeprefix("sweep_")
    return bridge_tests.sweep(seed, direction, f_range_hz=f_range_hz, input_noise=input_noise, **common)


def truth() -> TrueModes:
    """The deck modes of the simulating bridge model at every sensor channel."""
    t = bridge_tests.true_modes()
    return TrueModes(t["f_hz"], t["zeta"], t["shapes"], tuple(t["labels"]), t["deck_energy"],
                     tuple(t["dofs"]), t["mode_type"])


CAMPAIGN = Campaign("bridge", TESTS, record, truth, COMPONENTS)


def identified(case: str) -> MeasuredModes:
    """N4SID of a simulated shaker sweep, ``case`` bridge_vertical or bridge_lateral (module docstring)."""
    from framework.identification import pipeline as pl

    if case not in IDENTIFIED_CASES:
        raise InputError(f"identified bridge modes: unknown case {case!r}; known: {list(IDENTIFIED_CASES)}")
    direction = case.split("_", 1)[1]
    comp = "uz" if direction == "vertical" else "uy"
    full = bridge_tests.sweep(1 if direction == "vertical" else 2, direction)
    rec = full.select([c for c in full.output_labels if c.endswith(comp)])
    ident = pl.identify(rec, SETTINGS)
    return pl.to_measured_modes(
        ident.selected, f"bridge_{direction}_identified", source=f"N4SID of a simulated {direction} shaker sweep"
    )
