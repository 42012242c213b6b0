"""The simply supported concrete beam as a structure descriptor (SPEC 7).

:data:`BEAM` (``beam``): the beam model (:mod:`.model`; numpy or OpenSees backend, the numpy
model drawn from its OpenSees twin), simulated measurements of its damage states, the
effect catalogue (:mod:`.effects`) and the reproduction rows (:mod:`.reproduction`).
"""

from __future__ import annotations

from framework.structures.beam import effects, model, reproduction
from framework.structures.descriptor import StructureDescriptor

BEAM = StructureDescriptor(
    name="beam",
    title="simply supported concrete beam, 10/20 elements, damage states (SPEC 7)",
    make_model=model.make_model,
    measured=model.measured,
    cases=("base", *model.DAMAGE_STATES, "source_state1", "source_state2"),
    effects=effects.catalogue,
    reproduction=reproduction.rows,
)
