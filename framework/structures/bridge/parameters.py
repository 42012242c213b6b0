"""Updating parameters of the bridge: six ratios to the initial model (bounds 0.6-1.3).

``K_y_deck`` (vertical bending I), ``K_x_deck`` (lateral bending I), ``K_t_deck`` (torsion J),
``K_cable`` (E A of all cables, tension kept), ``T_Cab1`` (tension of the four Cab-1 cables),
``K_bearing`` (all bearing springs together).
"""

from __future__ import annotations

from framework.core.parameters import Parameter, ParameterSet

PARAMETER_NAMES = ("K_y_deck", "K_x_deck", "K_t_deck", "K_cable", "T_Cab1", "K_bearing")
_DESCRIPTIONS = {
    "K_y_deck": "deck vertical bending stiffness ratio (I about transverse axis)",
    "K_x_deck": "deck lateral bending stiffness ratio (I about vertical axis)",
    "K_t_deck": "deck torsional stiffness ratio (J)",
    "K_cable": "axial stiffness ratio E A of all cables (tensions kept)",
    "T_Cab1": "tension ratio of the four Cab-1 cables (nearest the abutments)",
    "K_bearing": "stiffness ratio of all bearing springs together",
}


def bridge_parameters(lower: float = 0.6, upper: float = 1.3) -> ParameterSet:
    """The six updating parameters, ratios to the initial model (initial 1)."""
    return ParameterSet(Parameter(name, 1.0, lower, upper, "-", _DESCRIPTIONS[name]) for name in PARAMETER_NAMES)
