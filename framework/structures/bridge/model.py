"""The bridge model factory :func:`make_model`: plain OpenSees path or fast eigen path.

Evaluation paths: ``make_model(fast=False)`` is the plain :class:`OpenSeesModel`;
``fast=True`` (default) is :class:`~framework.structures.bridge.fast.BridgeFastModel`, same
build and gravity, own eigen solution (~12x faster, same modes to ~1e-10).

Options: ``cable_elements``, ``lateral_restraint``, ``tensions``, ``deck_section`` of the build (see
:mod:`framework.structures.bridge.build`), ``n_modes`` of the plain eigen solution, and the
deck-mode selection shared by both paths:

- ``f_max_hz`` (default 15): deck modes above it are dropped;
- ``deck_energy_min`` (default 0.1): modes whose deck share of kinetic energy is below this
  are cable or pylon modes and are dropped, and so are longitudinal deck modes (both
  paths). The cable-dominated partner of the split 1st vertical pair has a deck share of
  only 0.12, hence the low threshold.
"""

from __future__ import annotations

import functools
import logging

from framework.models.base import ModalResult
from framework.models.opensees import OpenSeesModel
from framework.structures.bridge.build import GRAVITY, build_bridge, check_options
from framework.structures.bridge.fast import BridgeFastModel
from framework.structures.bridge.geometry import sensor_dofs
from framework.structures.bridge.modes import classify_and_keep_deck_modes
from framework.structures.bridge.parameters import bridge_parameters

log = logging.getLogger(__name__)

#: modes solved by the plain path per cable discretisation (cable modes crowd the band)
N_MODES_PLAIN = {1: 40, 2: 70, 4: 100, 8: 180}
#: deck modes above this frequency are dropped (both paths), Hz
F_MAX_HZ = 15.0


def _postprocess(result, info, ops, *, deck_energy_min: float, f_max_hz: float):
    """Plain-path postprocess: drop modes above f_max_hz, then classify and keep deck modes."""
    if result.frequencies_hz[-1] < f_max_hz:
        log.debug("plain path: highest computed mode %.2f Hz < f_max %.2f Hz", result.frequencies_hz[-1], f_max_hz)
    keep = result.frequencies_hz <= f_max_hz
    trimmed = ModalResult(result.frequencies_hz[keep], result.shapes[:, keep], result.dofs, meta=result.meta)
    return classify_and_keep_deck_modes(trimmed, info, ops, deck_energy_min)


def make_model(
    cable_elements: int = 4,
    fast: bool = True,
    *,
    lateral_restraint: str = "rigid",
    tensions: str = "installed",
    deck_section: str = "steel_overhangs",
    deck_energy_min: float = 0.1,
    f_max_hz: float = F_MAX_HZ,
    n_modes: int | None = None,
):
    """The bridge model: fast path (:class:`BridgeFastModel`) or plain :class:`OpenSeesModel`.

    Both return only deck modes (deck kinetic-energy share >= deck_energy_min) up to
    f_max_hz, with mode_info deck/cable/pylon_energy, mode_type and model_mode.
    """
    check_options(cable_elements, lateral_restraint, tensions, deck_section)
    build = functools.partial(
        build_bridge,
        cable_elements=cable_elements,
        lateral_restraint=lateral_restraint,
        tensions=tensions,
        deck_section=deck_section,
    )
    plain = OpenSeesModel(
        build=build,
        parameters=bridge_parameters(),
        measured_dofs=sensor_dofs(),
        n_modes=n_modes or N_MODES_PLAIN[cable_elements],
        gravity=GRAVITY,
        solver="scipy",
        postprocess=functools.partial(_postprocess, deck_energy_min=deck_energy_min, f_max_hz=f_max_hz),
        name=f"bridge_{cable_elements}el",
    )
    if not fast:
        return plain
    return BridgeFastModel(plain, deck_energy_min=deck_energy_min, f_max_hz=f_max_hz)
