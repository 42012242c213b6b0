"""The SMU benchmark structures as structure descriptors (data read from ../shared/benchmarks/smu).

- :data:`FOUR_STORY` (``four_story``): the four-storey shear frame and its identified modes
  (a :class:`~framework.models.shear_building.ShearBuilding`, drawn as stacked floors);
- :data:`FOOTBRIDGE` (``footbridge``): the 946-DOF steel footbridge and its five measured
  modes with standard deviations (no coordinates: shapes drawn channel by channel), and the
  reproduction rows of the SMU package's published optima (:mod:`.reproduction`).
"""

from __future__ import annotations

from framework.structures.descriptor import StructureDescriptor
from framework.structures.smu import model, reproduction

FOUR_STORY = StructureDescriptor(
    name="four_story",
    title="SMU four-storey shear frame (lbf, in, s)",
    make_model=model.make_four_story,
    measured=model.four_story_measured,
    cases=tuple(model.FOUR_STORY_CASES),
)

FOOTBRIDGE = StructureDescriptor(
    name="footbridge",
    title="SMU steel footbridge, 946-DOF substructure matrix model",
    make_model=model.make_footbridge,
    measured=model.footbridge_measured,
    cases=("base",),
    reproduction=reproduction.rows,
)
