"""The laboratory frame's two models as structure descriptors (SPEC 5).

Both are the structure ``lab_frame`` (family): configs name its measured data
(``measured: {builtin: lab_frame}``), effect catalogue (``structure: lab_frame`` in a
diagnosis) and simulated tests (``structure: lab_frame`` in an identification test) by it.

- :data:`THREE_DOF` (``lab_frame_3dof``): the 3-DOF analytical model (:mod:`.model`), its
  measured modes, its drawing (rigid slab, the model's ``geometry`` method), the simulated
  shake-table and snap-back tests (:mod:`.campaign`), the modes identified from them and
  the reproduction rows of the whole lab-frame study (:mod:`.reproduction`);
- :data:`DETAILED` (``lab_frame_detailed``): the detailed OpenSees model (:mod:`.detailed`),
  the same measured modes, its geometry (the built domain with sensors at the slab
  corners, :func:`.geometry.detailed_geometry`) and the effect catalogue (:mod:`.effects`).
"""

from __future__ import annotations

from framework.structures.descriptor import StructureDescriptor
from framework.structures.lab_frame import detailed, effects, geometry, model, reproduction


def campaign():
    """The simulated tests (:data:`.campaign.CAMPAIGN`; imported when asked: signal processing)."""
    from framework.structures.lab_frame.campaign import CAMPAIGN

    return CAMPAIGN


def identified():
    """N4SID of three simulated shake-table sweeps (:func:`.campaign.identified`)."""
    from framework.structures.lab_frame.campaign import identified

    return identified()


THREE_DOF = StructureDescriptor(
    name="lab_frame_3dof",
    title="laboratory frame, 3-DOF analytical model (SPEC 5)",
    make_model=model.make_model,
    measured=model.measured,
    cases=tuple(model.CASES),
    family="lab_frame",
    reproduction=reproduction.rows,
    tests=campaign,
    identified={"lab_frame": identified},
)

DETAILED = StructureDescriptor(
    name="lab_frame_detailed",
    title="laboratory frame, detailed OpenSees model (SPEC 5)",
    make_model=detailed.make_model,
    measured=detailed.measured,
    cases=tuple(model.CASES),
    family="lab_frame",
    effects=effects.catalogue,
    geometry=geometry.detailed_geometry,
)
