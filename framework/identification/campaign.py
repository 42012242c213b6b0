"""The simulated test campaign: which tests each structure has, their records, the true modes.

``TESTS[(structure, test)]`` describes a simulated test: whether it has a measured input (an
input-output test, for N4SID and FRF peak picking) or not (output only, for SSI-cov), its
default record length and sweep range, whether it is a free decay, and the channels the
identification uses by default (bridge: the component the test excites).

- lab frame: ``sweep`` (shake table, 0-15 Hz, 150 s), ``snap_back`` (free decay, 40 s);
- bridge: ``sweep_vertical`` / ``sweep_lateral`` (three shakers, 1-15 Hz, 391 s; uz / uy
  channels), ``jumping`` (300 s, output only; uz channels).

``simulate(...)`` gives one record (the seed draws the noise and the random excitation);
``true_modes(...)`` the modes of the simulating model that the identification must recover:
the modes in the identification band and, for the bridge, of the types the measured
component sees (uz: vertical and torsional, uy: lateral and torsional).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from framework.core.errors import InputError
from framework.identification.records import VibrationRecord
from framework.structures.bridge import vibration_tests as bridge_tests
from framework.structures.lab_frame import model as lab_frame
from framework.structures.lab_frame import vibration_tests as lab_tests


@dataclass(frozen=True)
class SimulatedTest:
    has_input: bool
    duration_s: float
    f_range_hz: tuple[float, float] | None = None  # sweeps only
    free_decay: bool = False
    component: str = "all"  # channels identified by default: "all" or a DOF suffix ("uz", "uy")


TESTS: dict[tuple[str, str], SimulatedTest] = {
    ("lab_frame", "sweep"): SimulatedTest(True, 150.0, (0.0, 15.0)),
    ("lab_frame", "snap_back"): SimulatedTest(False, 40.0, free_decay=True),
    ("bridge", "sweep_vertical"): SimulatedTest(True, bridge_tests.SWEEP_DURATION_S, bridge_tests.SWEEP_RANGE_HZ,
                                           component="uz"),
    ("bridge", "sweep_lateral"): SimulatedTest(True, bridge_tests.SWEEP_DURATION_S, bridge_tests.SWEEP_RANGE_HZ,
                                          component="uy"),
    ("bridge", "jumping"): SimulatedTest(False, 300.0, component="uz"),
}
#: components a structure's channels can be restricted to ("all": every output channel)
COMPONENTS = {"lab_frame": ("all",), "bridge": ("all", "uz", "uy")}


def simulated_test(structure: str, test: str) -> SimulatedTest:
    try:
        return TESTS[(structure, test)]
    except KeyError:
        known = sorted(t for s, t in TESTS if s == structure)
        raise InputError(f"test {test!r} is not a test of structure {structure!r}; known: {known}") from None


def simulate(
    structure: str,
    test: str,
    seed: int,
    duration_s: float,
    sampling_hz: float,
    output_noise: float,
    input_noise: float | None = None,
    f_range_hz: Sequence[float] | None = None,
    component: str = "all",
) -> VibrationRecord:
    """One simulated record of ``test`` on ``structure`` (only the channels of ``component``)."""
    tt = simulated_test(structure, test)
    f_range = tuple(f_range_hz) if f_range_hz is not None else tt.f_range_hz
    common = {"duration_s": duration_s, "output_noise": output_noise, "sampling_hz": sampling_hz}
    if structure == "lab_frame":
        if test == "sweep":
            rec = lab_tests.sweep(seed, f_range_hz=f_range, input_noise=input_noise, **common)
        else:
            rec = lab_tests.snap_back(seed, **common)
    elif test == "jumping":
        rec = bridge_tests.jumping(seed, **common)
    else:
        direction = test.removeprefix("sweep_")
        rec = bridge_tests.sweep(seed, direction, f_range_hz=f_range, input_noise=input_noise, **common)
    if component == "all":
        return rec
    return rec.select([c for c in rec.output_labels if c.endswith(f"_{component}")])


def channels(structure: str, component: str = "all") -> tuple[str, ...]:
    """The output channels of ``structure``'s records restricted to ``component``."""
    names = lab_frame.DOFS if structure == "lab_frame" else bridge_tests.true_modes()["dofs"]
    return tuple(names) if component == "all" else tuple(c for c in names if c.endswith(f"_{component}"))


@dataclass(frozen=True)
class TrueModes:
    """Modes of the simulating model at the record's channels: f_hz (m,), zeta (m,),
    shapes (n_channels, m), labels, deck_energy (m,) (bridge: kinetic-energy share of the
    deck) or None."""

    f_hz: np.ndarray
    zeta: np.ndarray
    shapes: np.ndarray
    labels: tuple[str, ...]
    deck_energy: np.ndarray | None = None


def true_modes(structure: str, channels: Sequence[str], band_hz: Sequence[float], component: str = "all") -> TrueModes:
    """The true modes in ``band_hz`` seen by ``channels`` (bridge: of the component's types)."""
    lo, hi = band_hz
    if structure == "lab_frame":
        f, zeta, shapes = lab_tests.true_modes()
        rows = [lab_frame.DOFS.index(c) for c in channels]
        keep = np.flatnonzero((f >= lo) & (f <= hi))
        return TrueModes(f[keep], zeta[keep], shapes[np.ix_(rows, keep)],
                         tuple(lab_tests.MODE_LABELS[k] for k in keep))
    truth = bridge_tests.true_modes()
    rows = [truth["dofs"].index(c) for c in channels]
    in_band = (truth["f_hz"] >= lo) & (truth["f_hz"] <= hi)
    if component != "all":
        in_band &= np.isin(truth["mode_type"], bridge_tests.COMPONENT_MODE_TYPES[component])
    keep = np.flatnonzero(in_band)
    return TrueModes(truth["f_hz"][keep], truth["zeta"][keep], truth["shapes"][np.ix_(rows, keep)],
                     tuple(truth["labels"][k] for k in keep), truth["deck_energy"][keep])
