"""Effect catalogue of the laboratory frame (detailed OpenSeesPy model, SPEC 5).

Model under test: :mod:`framework.structures.lab_frame.detailed` with *rigid* bracket joints
(the bracket rotational springs set to ``RIGID_FACTOR`` times the column's E I / L, i.e.
effectively clamped column ends) and one base parameter, ``column_stiffness_ratio``
(E and G of the columns, bounds 0.7-1.3). Measured: the three lowest modes at the slab
centre (y, x, torsion x b/2).

Candidate effects:

- ``semi_rigid_joints``: bracket rotational flexibility about x (k_r2, sway in y) and
  about y (k_r3, sway in x), as relative flexibilities f = (E I / L)_column / k, so that
  f = 0 is the rigid joint (null value) and the SPEC's initial brackets are f_r2 = 1.83,
  f_r3 = 0.04. k = (E I / L) / (f + 1 / RIGID_FACTOR).
- ``sensor_mass_eccentricity``: a sensor package of ``SENSOR_MASS_KG`` assumed at the
  slab centre sits at (x, y); parameters ``sensor_x_m``, ``sensor_y_m`` in [-0.3, 0.3] m
  (null 0). The mass is taken off the centre node and spread over the four slab nodes
  around (x, y) with bilinear weights (exact total mass and static moments).
"""

from __future__ import annotations

import functools
from collections.abc import Mapping

import numpy as np

from framework.core.errors import ModelEvaluationError
from framework.core.parameters import Parameter, ParameterSet
from framework.diagnosis.effects import Catalogue, Effect
from framework.models.opensees import OpenSeesModel, ops_module
from framework.structures.lab_frame import detailed as lab

#: rotational stiffness of a "rigid" joint, as a multiple of the column's E I / L
RIGID_FACTOR = 1000.0
COLUMN_EI_OVER_L_N_M = lab.ALU_E_PA * lab.COLUMN_I_M4 / lab.HEIGHT_M
#: mass of the sensor package (accelerometers, mounts, cables) of the eccentricity effect
SENSOR_MASS_KG = 0.8
MESH = 4

BASE_PARAMETERS = ParameterSet(
    [Parameter("column_stiffness_ratio", 1.0, 0.7, 1.3, "-", "E and G multiplier of the columns")]
)

EFFECTS = {
    "semi_rigid_joints": Effect(
        "semi_rigid_joints",
        "rotational flexibility of the bracket joints (k_r2 about x, k_r3 about y)",
        (
            Parameter("flex_r2", 0.0, 0.0, 5.0, "-", "(EI/L)_column / k_r2 (0 = rigid)"),
            Parameter("flex_r3", 0.0, 0.0, 5.0, "-", "(EI/L)_column / k_r3 (0 = rigid)"),
        ),
        hidden_values={"flex_r2": (1.2, 2.5), "flex_r3": (0.3, 1.0)},
    ),
    "sensor_mass_eccentricity": Effect(
        "sensor_mass_eccentricity",
        f"a {SENSOR_MASS_KG:g} kg sensor package off the slab centre at (x, y)",
        (
            Parameter("sensor_x_m", 0.0, -0.3, 0.3, "m", "x of the sensor package"),
            Parameter("sensor_y_m", 0.0, -0.3, 0.3, "m", "y of the sensor package"),
        ),
        hidden_values={"sensor_x_m": (0.18, 0.28), "sensor_y_m": (-0.28, -0.18)},
    ),
}


def joint_stiffness_n_m(flex: float) -> float:
    """k = (E I / L)_column / (f + 1 / RIGID_FACTOR)."""
    return COLUMN_EI_OVER_L_N_M / (flex + 1.0 / RIGID_FACTOR)


def bilinear_weights(x_m: float, y_m: float, mesh: int = MESH) -> dict[tuple[int, int], float]:
    """Slab-grid nodes (i, j) around (x, y) and their bilinear weights (sum 1)."""
    h = lab.SLAB_WIDTH_M / mesh
    u = np.clip((x_m + lab.SLAB_WIDTH_M / 2) / h, 0.0, mesh - 1e-9)
    v = np.clip((y_m + lab.SLAB_WIDTH_M / 2) / h, 0.0, mesh - 1e-9)
    i, j = int(u), int(v)
    a, b = u - i, v - j
    return {
        (i, j): (1 - a) * (1 - b),
        (i + 1, j): a * (1 - b),
        (i, j + 1): (1 - a) * b,
        (i + 1, j + 1): a * b,
    }


def build(values: Mapping[str, float], *, joints: str = "rigid", eccentric: bool = False) -> dict:
    """Build the detailed frame with rigid or semi-rigid joints and an optional eccentric sensor mass."""
    brackets = dict(lab.BRACKET_STIFFNESS)
    f2 = values.get("flex_r2", 0.0) if joints == "semi_rigid" else 0.0
    f3 = values.get("flex_r3", 0.0) if joints == "semi_rigid" else 0.0
    brackets["k_r2"] = joint_stiffness_n_m(f2)
    brackets["k_r3"] = joint_stiffness_n_m(f3)
    brackets["k_r1"] = max(brackets["k_r1"], joint_stiffness_n_m(0.0)) if joints == "rigid" else brackets["k_r1"]
    info = lab.build(brackets, mesh=MESH, column_stiffness_ratio=float(values["column_stiffness_ratio"]))
    if eccentric:
        ops = ops_module()
        masses = dict(info["point_masses"])
        centre = info["centre_node"]
        if masses.get(centre, 0.0) < SENSOR_MASS_KG:
            raise ModelEvaluationError("bad_mass", f"centre node mass {masses.get(centre)} < {SENSOR_MASS_KG} kg")
        masses[centre] -= SENSOR_MASS_KG
        for (i, j), w in bilinear_weights(values["sensor_x_m"], values["sensor_y_m"]).items():
            tag = lab.slab_node(i, j, MESH)
            masses[tag] = masses.get(tag, 0.0) + SENSOR_MASS_KG * w
        for tag, m in masses.items():
            ops.mass(tag, m, m, m, 0.0, 0.0, 0.0)
        info["point_masses"] = masses
    return info


def make_model(active: Mapping[str, str]) -> OpenSeesModel:
    """The frame with the ``active`` effects as an OpenSeesModel."""
    items = list(BASE_PARAMETERS)
    for name in EFFECTS:
        if name in active:
            items.extend(EFFECTS[name].parameters)
    centre = lab.slab_node(MESH // 2, MESH // 2, MESH)
    joints = "semi_rigid" if "semi_rigid_joints" in active else "rigid"
    eccentric = "sensor_mass_eccentricity" in active
    return OpenSeesModel(
        build=functools.partial(build, joints=joints, eccentric=eccentric),
        parameters=ParameterSet(items),
        measured_dofs={"y": (centre, "uy"), "x": (centre, "ux"), "torsion": (centre, "rz")},
        n_modes=3,
        solver="scipy",
        dof_scale={"torsion": lab.SLAB_WIDTH_M / 2},
        name=f"lab_frame_detailed[{joints}{', eccentric sensors' if eccentric else ''}]",
    )


def catalogue() -> Catalogue:
    """The lab frame's catalogue (model under test: rigid joints, column stiffness only)."""
    return Catalogue(
        structure="lab_frame",
        base_parameters=BASE_PARAMETERS,
        effects=EFFECTS,
        factory=make_model,
        n_measured_modes=3,
        description="detailed OpenSees lab frame, rigid joints; 3 modes at the slab centre (y, x, torsion)",
    )
