"""A three-storey, two-bay plane steel frame in OpenSeesPy (the diagnosis study's own structure).

Geometry (ours, a typical office frame): bays of 6.0 m and 4.0 m (column lines A, B, C at
x = 0, 6, 10 m), storey heights 4.0, 3.5, 3.5 m, columns fixed at the base. Elastic
beam-columns, E = 210 GPa: columns HEB 300 (A = 149 cm^2, I = 25 170 cm^4; the interior
line B HEB 340, A = 171 cm^2, I = 36 660 cm^4), beams IPE 400 (A = 84.5 cm^2,
I = 23 130 cm^4), each beam in two elements (a mid-span node). Floor mass 1.5 t/m along
the beams (roof 1.0 t/m) lumped at the nodes (tributary lengths), horizontal and vertical.

Parameters (the model under test): ``column_stiffness_ratio`` and ``beam_stiffness_ratio``
(E multipliers, 0.7-1.3). Measured: the six lowest modes at the left node of each floor
(x) and the beams' mid-span nodes (y). Its effect catalogue is :mod:`.effects`.
"""

from __future__ import annotations

from collections.abc import Mapping

from framework.core.parameters import Parameter, ParameterSet
from framework.models.opensees import OpenSeesModel, ops_module

E_PA = 210e9
BAYS_M = (6.0, 4.0)
STOREYS_M = (4.0, 3.5, 3.5)
COLUMN = (149e-4, 25170e-8)  # HEB 300: A (m^2), I (m^4)
COLUMN_INNER = (171e-4, 36660e-8)  # HEB 340
BEAM = (84.5e-4, 23130e-8)  # IPE 400
FLOOR_MASS_KG_M = 1500.0
ROOF_MASS_KG_M = 1000.0
#: axial stiffness of the two-storey brace at its true value = ratio * k_column
BRACE_AREA_M2 = 10e-4

PARAMETERS = ParameterSet([
    Parameter("column_stiffness_ratio", 1.0, 0.7, 1.3, "-", "E multiplier of the columns"),
    Parameter("beam_stiffness_ratio", 1.0, 0.7, 1.3, "-", "E multiplier of the beams"),
])  # fmt: skip


def node_tag(line: int, level: int) -> int:
    """Column line 0..2 (A, B, C) at level 0..3."""
    return 100 * level + 10 * line + 1


def mid_tag(bay: int, level: int) -> int:
    return 100 * level + 10 * bay + 5


def xs() -> list[float]:
    return [0.0, BAYS_M[0], BAYS_M[0] + BAYS_M[1]]


def zs() -> list[float]:
    out = [0.0]
    for h in STOREYS_M:
        out.append(out[-1] + h)
    return out


def build(values: Mapping[str, float], brace: float = 0.0) -> dict:
    """Build the frame; ``brace`` > 0 adds the two-storey diagonal of area brace * BRACE_AREA_M2."""
    ops = ops_module()
    ops.model("basic", "-ndm", 2, "-ndf", 3)
    x, z = xs(), zs()
    for lv, zz in enumerate(z):
        for ln, xx in enumerate(x):
            ops.node(node_tag(ln, lv), xx, zz)
        if lv:
            for bay in range(2):
                ops.node(mid_tag(bay, lv), (x[bay] + x[bay + 1]) / 2, zz)
    for ln in range(3):
        ops.fix(node_tag(ln, 0), 1, 1, 1)
    ops.geomTransf("Linear", 1)
    ec = E_PA * float(values["column_stiffness_ratio"])
    eb = E_PA * float(values["beam_stiffness_ratio"])
    tag = 1
    for lv in range(1, 4):
        for ln in range(3):
            a, i = COLUMN_INNER if ln == 1 else COLUMN
            ops.element("elasticBeamColumn", tag, node_tag(ln, lv - 1), node_tag(ln, lv), a, ec, i, 1)
            tag += 1
    for lv in range(1, 4):
        for bay in range(2):
            a, i = BEAM
            ops.element("elasticBeamColumn", tag, node_tag(bay, lv), mid_tag(bay, lv), a, eb, i, 1)
            ops.element("elasticBeamColumn", tag + 1, mid_tag(bay, lv), node_tag(bay + 1, lv), a, eb, i, 1)
            tag += 2
    for lv in range(1, 4):
        w = ROOF_MASS_KG_M if lv == 3 else FLOOR_MASS_KG_M
        for ln in range(3):
            trib = sum(BAYS_M[b] / 4 for b in (ln - 1, ln) if 0 <= b < 2)
            ops.mass(node_tag(ln, lv), w * trib, w * trib, 0.0)
        for bay in range(2):
            m = w * BAYS_M[bay] / 2
            ops.mass(mid_tag(bay, lv), m, m, 0.0)
    if brace > 0:
        ops.uniaxialMaterial("Elastic", 1, E_PA)
        ops.element("Truss", 1000, node_tag(0, 0), node_tag(1, 2), brace * BRACE_AREA_M2, 1)
    return {}


MEASURED_DOFS = {f"x{lv}": (node_tag(0, lv), "ux") for lv in (1, 2, 3)} | {
    f"y{lv}{'ab'[bay]}": (mid_tag(bay, lv), "uy") for lv in (1, 2, 3) for bay in range(2)
}


def model(brace: bool = False) -> OpenSeesModel:
    """The frame (model under test; ``brace``: with the two-storey brace, parameter ``two_storey_brace_area``)."""
    params = list(PARAMETERS)
    if brace:
        params.append(Parameter("two_storey_brace_area", 0.0, 0.0, 5.0, "-", f"area / {BRACE_AREA_M2 * 1e4:g} cm^2"))
    fn = _build_braced if brace else build
    return OpenSeesModel(fn, ParameterSet(params), MEASURED_DOFS, n_modes=8, name="frame_two_bay")


def _build_braced(values: Mapping[str, float]) -> dict:
    return build(values, brace=float(values["two_storey_brace_area"]))
