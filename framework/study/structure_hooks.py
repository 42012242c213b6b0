"""What the study layer hands from a structure's descriptor to the layers below it.

The report layer imports no structure: the study passes the structure's features in.
:func:`with_structure_choices` gives the report's ``choices`` analysis the named
structure's ``modelling_choices``; :func:`geometry_of` gives the shape tables the
structure's geometry hook (None for a model that draws itself or has its OpenSees domain).
"""

from __future__ import annotations

from framework.structures.registry import STRUCTURES, describe, modelling_choices


def with_structure_choices(report: dict) -> dict:
    """``report`` with the ``choices`` analysis's structure resolved to its ``modelling_choices``."""
    choices = report.get("choices")
    if not isinstance(choices, dict) or not choices.get("structure"):
        return report
    function = modelling_choices(choices["structure"].get("name"))
    return {**report, "choices": {**choices, "modelling_choices": function}}


def geometry_of(name: str):
    """The geometry hook of structure ``name`` (a built-in or a user's ``module:function``), or None."""
    if name in STRUCTURES:
        return STRUCTURES[name].geometry
    return describe(name).geometry if isinstance(name, str) and ":" in name else None
