"""The cable-stayed footbridge as a structure descriptor (SPEC 6).

:data:`BRIDGE` (``bridge``): the OpenSeesPy model (:mod:`.model`; its fast path is drawn
from the plain model's built domain), the measured modes with reference shapes
(:mod:`.reference`), the effect catalogue (:mod:`.effects`), the modelling choices
(:mod:`.choices`), the simulated shaker and jumping tests and the modes identified from them
(:mod:`.campaign`) and the reproduction rows (:mod:`.reproduction`).
"""

from __future__ import annotations

from framework.structures.bridge import choices, effects, model, reference, reproduction
from framework.structures.descriptor import StructureDescriptor


def campaign():
    """The simulated tests (:data:`.campaign.CAMPAIGN`; imported when asked: signal processing)."""
    from framework.structures.bridge.campaign import CAMPAIGN

    return CAMPAIGN


def identified_vertical():
    """N4SID of the simulated vertical shaker sweep."""
    from framework.structures.bridge.campaign import identified

    return identified("bridge_vertical")


def identified_lateral():
    """N4SID of the simulated lateral shaker sweep."""
    from framework.structures.bridge.campaign import identified

    return identified("bridge_lateral")


BRIDGE = StructureDescriptor(
    name="bridge",
    title="cable-stayed pedestrian bridge, OpenSeesPy model (SPEC 6)",
    make_model=model.make_model,
    measured=reference.measured,
    cases=("base", "peak"),
    effects=effects.catalogue,
    reproduction=reproduction.rows,
    tests=campaign,
    modelling_choices=choices.modelling_choices,
    identified={"bridge_vertical": identified_vertical, "bridge_lateral": identified_lateral},
)
