"""A user's own OpenSeesPy model for `gomu diagnose` (examples/diagnosis, docs/tutorials/diagnosis.md).

A two-storey, one-bay plane steel frame, 5 m wide, storeys of 3.5 m, fixed at the base;
floor masses lumped at the beam ends and at the beams' mid-span nodes. Two parameters:
the E multipliers of the columns and of the beams.

- ``model()`` returns the OpenSeesModel: enough for ``candidates: auto``.
- ``catalogue()`` adds one hand-written candidate effect (``heavy_equipment``: a mass on
  the roof's mid-span node) to show every field of an Effect; combine it with the generated
  candidates by ``candidates: [auto, heavy_equipment]``.
"""

from __future__ import annotations

import openseespy.opensees as ops

from framework.core.parameters import Parameter, ParameterSet
from framework.diagnosis.effects import Catalogue, Effect
from framework.models.opensees import OpenSeesModel

E_PA = 210e9
COLUMN = (149e-4, 25170e-8)  # HEB 300: area (m^2), second moment (m^4)
BEAM = (84.5e-4, 23130e-8)  # IPE 400
FLOOR_MASS_KG = 6000.0  # per floor, half at the mid-span node, a quarter at each beam end


def build(values: dict) -> None:
    """Create the frame in the OpenSees domain from parameter values (SI units)."""
    ops.model("basic", "-ndm", 2, "-ndf", 3)
    for level in range(3):
        ops.node(10 * level + 1, 0.0, 3.5 * level)
        ops.node(10 * level + 2, 5.0, 3.5 * level)
    for level in (1, 2):
        ops.node(10 * level + 5, 2.5, 3.5 * level)
    ops.fix(1, 1, 1, 1)
    ops.fix(2, 1, 1, 1)
    ops.geomTransf("Linear", 1)
    ec = E_PA * values["column_stiffness_ratio"]
    eb = E_PA * values["beam_stiffness_ratio"]
    tag = 1
    for level in (1, 2):
        for line in (1, 2):
            ops.element("elasticBeamColumn", tag, 10 * (level - 1) + line, 10 * level + line, *COLUMN[:1], ec,
                        COLUMN[1], 1)
            tag += 1
        for a, b in ((10 * level + 1, 10 * level + 5), (10 * level + 5, 10 * level + 2)):
            ops.element("elasticBeamColumn", tag, a, b, BEAM[0], eb, BEAM[1], 1)
            tag += 1
        extra = values.get("equipment_mass_kg", 0.0) if level == 2 else 0.0
        ops.mass(10 * level + 1, FLOOR_MASS_KG / 4, FLOOR_MASS_KG / 4, 0.0)
        ops.mass(10 * level + 2, FLOOR_MASS_KG / 4, FLOOR_MASS_KG / 4, 0.0)
        m = FLOOR_MASS_KG / 2 + extra
        ops.mass(10 * level + 5, m, m, 0.0)


PARAMETERS = [
    Parameter("column_stiffness_ratio", 1.0, 0.7, 1.3, "-", "E multiplier of the columns"),
    Parameter("beam_stiffness_ratio", 1.0, 0.7, 1.3, "-", "E multiplier of the beams"),
]
#: what the test measured: {label: (node, direction)}
SENSORS = {"x1": (11, "ux"), "x2": (21, "ux"), "y1": (15, "uy"), "y2": (25, "uy")}


def model() -> OpenSeesModel:
    """The model under test (for ``candidates: auto``)."""
    return OpenSeesModel(build, ParameterSet(PARAMETERS), SENSORS, n_modes=6, name="my_frame")


# ---- a hand-written catalogue -------------------------------------------------------------
HEAVY_EQUIPMENT = Effect(
    name="heavy_equipment",
    description="equipment of unknown mass on the roof's mid-span node",
    # one parameter; its initial value (0) is the null value: the model without the effect
    parameters=(Parameter("equipment_mass_kg", 0.0, 0.0, 3000.0, "kg", "mass added at node 25"),),
    variants=("",),  # one location; several would be e.g. ("node15", "node25") read by the factory
    hidden_values={"equipment_mass_kg": (800.0, 1500.0)},  # only for simulated data (gomu run studies)
    expected_sign={"equipment_mass_kg": +1},  # physics: mass can only be added
)


def factory(active: dict, **options) -> OpenSeesModel:
    """The model with the ``active`` hand-written effects {name: variant}: base parameters first,
    then the active effects' parameters (inactive effects keep their null values)."""
    params = list(PARAMETERS)
    if "heavy_equipment" in active:
        params += list(HEAVY_EQUIPMENT.parameters)
    return OpenSeesModel(build, ParameterSet(params), SENSORS, n_modes=6, name="my_frame")


def catalogue() -> Catalogue:
    """Base parameters, candidate effects and the factory (``structure: my_frame:catalogue``)."""
    return Catalogue(
        structure="my_frame",
        base_parameters=ParameterSet(PARAMETERS),
        effects={"heavy_equipment": HEAVY_EQUIPMENT},
        factory=factory,
        n_measured_modes=4,
    )
