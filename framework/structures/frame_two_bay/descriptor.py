"""The three-storey two-bay steel frame as a structure descriptor (the diagnosis study's own).

:data:`FRAME_TWO_BAY` (``frame_two_bay``): the OpenSees frame (:mod:`.model`, drawn from its
built domain) and its effect catalogue (:mod:`.effects`: hand-written ``two_storey_brace``
plus generated candidates). It has no measured data: its diagnoses generate data with
hidden effects.
"""

from __future__ import annotations

from framework.structures.descriptor import StructureDescriptor
from framework.structures.frame_two_bay import effects, model

FRAME_TWO_BAY = StructureDescriptor(
    name="frame_two_bay",
    title="three-storey two-bay plane steel frame, OpenSeesPy (diagnosis study)",
    make_model=model.model,
    effects=effects.catalogue,
)
