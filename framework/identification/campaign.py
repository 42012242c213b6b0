"""A structure's simulated test campaign: its tests, their records, the true modes to recover.

A structure that can be tested in simulation describes its campaign with a :class:`Campaign`
(in its package, e.g. :mod:`framework.structures.lab_frame.campaign`) and hands it to the
framework through its descriptor (``StructureDescriptor.tests``); the ``identification``
run kind asks the descriptor, never a structure's module. A :class:`SimulatedTest` says
whether the test has a measured input (input-output: N4SID and FRF peak picking) or not
(output only: SSI-cov), its default record length and sweep range, whether it is a free
decay, and the channels identified by default (a DOF suffix such as ``uz``, or ``all``).

:meth:`Campaign.simulate` gives one record (the seed draws the noise and any random
excitation), restricted to the channels of a component; :meth:`Campaign.true_modes` the
modes of the simulating model that the identification must recover: those in the
identification band and, for a component, of the mode types its channels see.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from framework.core.errors import InputError
from framework.identification.records import VibrationRecord


@dataclass(frozen=True)
class SimulatedTest:
    has_input: bool
    duration_s: float
    f_range_hz: tuple[float, float] | None = None  # sweeps only
    free_decay: bool = False
    component: str = "all"  # channels identified by default: "all" or a DOF suffix ("uz", "uy")


@dataclass(frozen=True)
class TrueModes:
    """Modes of the simulating model at the record's channels: f_hz (m,), zeta (m,),
    shapes (n_channels, m), labels, deck_energy (m,) (bridge: kinetic-energy share of the
    deck) or None; ``channels`` the rows of ``shapes`` and ``mode_types`` (m,) or None."""

    f_hz: np.ndarray
    zeta: np.ndarray
    shapes: np.ndarray
    labels: tuple[str, ...]
    deck_energy: np.ndarray | None = None
    channels: tuple[str, ...] = ()
    mode_types: np.ndarray | None = None


@dataclass(frozen=True)
class Campaign:
    """The simulated tests of one structure.

    structure: its name in a config's ``tests.<label>.structure``; tests: {test name:
    SimulatedTest}; record(test, seed, *, duration_s, sampling_hz, output_noise, input_noise,
    f_range_hz) -> VibrationRecord with every output channel; truth() -> TrueModes of every
    mode of the simulating model at every output channel (``channels`` set);
    components: {component: mode types its channels see, or None for every type}; a
    component other than "all" keeps the channels whose name ends in ``_<component>``.
    """

    structure: str
    tests: Mapping[str, SimulatedTest]
    record: Callable[..., VibrationRecord]
    truth: Callable[[], TrueModes]
    components: Mapping[str, tuple[str, ...] | None] = field(default_factory=lambda: {"all": None})

    def test(self, name: str) -> SimulatedTest:
        try:
            return self.tests[name]
        except KeyError:
            raise InputError(f"test {name!r} is not a test of structure {self.structure!r}; "
                             f"known: {sorted(self.tests)}") from None

    def simulate(
        self,
        test: str,
        seed: int,
        duration_s: float,
        sampling_hz: float,
        output_noise: float,
        input_noise: float | None = None,
        f_range_hz: Sequence[float] | None = None,
        component: str = "all",
    ) -> VibrationRecord:
        """One simulated record of ``test`` (only the channels of ``component``)."""
        tt = self.test(test)
        f_range = tuple(f_range_hz) if f_range_hz is not None else tt.f_range_hz
        rec = self.record(test, seed, duration_s=duration_s, sampling_hz=sampling_hz, output_noise=output_noise,
                          input_noise=input_noise, f_range_hz=f_range)
        if component == "all":
            return rec
        return rec.select([c for c in rec.output_labels if c.endswith(f"_{component}")])

    def channels(self, component: str = "all") -> tuple[str, ...]:
        """The output channels of the records restricted to ``component``."""
        names = self.truth().channels
        return tuple(names) if component == "all" else tuple(c for c in names if c.endswith(f"_{component}"))

    def true_modes(self, channels: Sequence[str], band_hz: Sequence[float], component: str = "all") -> TrueModes:
        """The true modes in ``band_hz`` seen by ``channels`` (a component: of the types it sees)."""
        lo, hi = band_hz
        truth = self.truth()
        rows = [truth.channels.index(c) for c in channels]
        keep = (truth.f_hz >= lo) & (truth.f_hz <= hi)
        types = self.components.get(component)
        if types is not None and truth.mode_types is not None:
            keep &= np.isin(truth.mode_types, types)
        keep = np.flatnonzero(keep)
        return TrueModes(truth.f_hz[keep], truth.zeta[keep], truth.shapes[np.ix_(rows, keep)],
                         tuple(truth.labels[k] for k in keep),
                         None if truth.deck_energy is None else truth.deck_energy[keep], tuple(channels),
                         None if truth.mode_types is None else truth.mode_types[keep])
