"""Effect catalogue of the two-bay frame (the diagnosis study's own structure).

One hand-written effect, ``two_storey_brace`` (a diagonal from the base of line A to level 2
of line B; no generated candidate spans two storeys, so it is the study's out-of-candidate
case), plus the candidates generated from the model (:func:`framework.diagnosis.auto.with_auto`).
"""

from __future__ import annotations

import functools

from framework.core.parameters import Parameter
from framework.diagnosis.auto import with_auto
from framework.diagnosis.effects import Catalogue, Effect
from framework.structures.frame_two_bay.model import PARAMETERS, model


def _factory(active, **_):
    return model(brace="two_storey_brace" in active)


#: hidden (variants, value range) of the generated candidates in the diagnosis study's data
HIDDEN = {
    "member_stiffness_change": (("ele1", "ele2", "ele3", "ele4", "ele5", "ele6"), (-0.6, -0.4)),
    "added_brace": (None, (1.0, 2.0)),
    "level_mass_change": (None, (0.25, 0.4)),
    "semi_rigid_connections": (("all",), (0.5, 1.0)),
    "support_rotational_flexibility": (("all",), (0.5, 1.0)),
}


@functools.lru_cache(maxsize=2)
def catalogue(candidates: str = "auto"):
    """The frame's catalogue: hand-written ``two_storey_brace`` + generated candidates."""
    hand = Catalogue(
        structure="frame_two_bay",
        base_parameters=PARAMETERS,
        effects={
            "two_storey_brace": Effect(
                "two_storey_brace",
                "a diagonal from the base of line A to level 2 of line B (spans two storeys)",
                (Parameter("two_storey_brace_area", 0.0, 0.0, 5.0, "-", "area / 10 cm^2"),),
                hidden_values={"two_storey_brace_area": (1.0, 2.0)},
            )
        },
        factory=_factory,
        n_measured_modes=6,
        description="three-storey two-bay OpenSees frame; 6 modes at 9 DOFs",
    )
    return with_auto(hand, HIDDEN)
