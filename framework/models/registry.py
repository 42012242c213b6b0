"""Built-in structures and measured data sets, by name.

A structure module exposes ``make_model(**options) -> StructuralModel`` and
``measured(case="base") -> MeasuredModes``. Entries are import paths so that importing
the registry stays cheap (OpenSees is only loaded when an OpenSees structure is used).
A user's own model is given in a config as ``structure: {name: "my_pkg.my_mod:make_model"}``.
"""

from __future__ import annotations

import importlib

from framework.errors import InputError

STRUCTURES: dict[str, str] = {
    "lab_frame_3dof": "framework.models.lab_frame:make_model",
    "lab_frame_detailed": "framework.models.lab_frame_detailed:make_model",
    "bridge": "framework.models.bridge:make_model",
    "beam": "framework.models.beam:make_model",
    "four_story": "framework.models.smu:make_four_story",
    "footbridge": "framework.models.smu:make_footbridge",
}

MEASUREMENTS: dict[str, str] = {
    "lab_frame": "framework.models.lab_frame:measured",
    "bridge": "framework.models.bridge:measured",
    "beam": "framework.models.beam:measured",
    "identified": "framework.identification.datasets:measured",
    "four_story": "framework.models.smu:four_story_measured",
    "footbridge": "framework.models.smu:footbridge_measured",
}


def resolve(path: str, what: str):
    """Import ``module:attribute``; errors name the entry."""
    if ":" not in path:
        raise InputError(f"{what}: {path!r} is neither a built-in name nor 'module:function'")
    module, attr = path.split(":", 1)
    try:
        return getattr(importlib.import_module(module), attr)
    except (ImportError, AttributeError) as exc:
        raise InputError(f"{what}: cannot import {path!r}: {exc}") from exc


def make_structure(name: str, **options):
    """Build structure ``name`` (built-in name or 'module:function') with options."""
    factory = resolve(STRUCTURES.get(name, name), f"structure.name={name!r}")
    try:
        return factory(**options)
    except TypeError as exc:
        raise InputError(f"structure {name!r}: bad options {sorted(options)}: {exc}") from exc


def builtin_measured(name: str, case: str = "base"):
    """Measured data set ``name`` (built-in name or 'module:function') for ``case``."""
    if name not in MEASUREMENTS and ":" not in name:
        raise InputError(f"measured.builtin={name!r} unknown; known: {sorted(MEASUREMENTS)}")
    return resolve(MEASUREMENTS.get(name, name), f"measured.builtin={name!r}")(case)
