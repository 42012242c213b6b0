"""What the framework knows of a structure: one typed descriptor, the same for a built-in and a user's model.

A structure package (``framework/structures/<name>/``) describes each of its models with a
:class:`StructureDescriptor` in its ``descriptor.py`` and adds one line to
:mod:`framework.structures.registry`. Every feature of the framework asks the descriptor,
never the structure's modules or class names:

- ``gomu run`` builds the model (``make_model``) and loads its measured data (``measured``);
- the shape stage draws the model's modes with ``geometry`` (or, without a hook, the
  model's own ``geometry`` method or its built OpenSees domain, :mod:`framework.models.geometry`);
- ``gomu diagnose`` takes its effect catalogue (``effects``) or generates candidates from
  an OpenSees model (``candidates: auto``);
- the identification kind simulates its vibration tests (``tests``); ``identified`` data sets
  are the modes identified from them (``measured: {builtin: identified, case: ...}``);
- the report's ``choices`` analysis lists its ``modelling_choices``; ``gomu report
  --reproduction`` adds its ``reproduction`` rows to docs/reproduction.md.

Only ``name``, ``title`` and ``make_model`` are required. A user's model named in a config
as ``module:function`` is described by the same type
(:func:`framework.structures.references.describe_reference`), so it takes the same code
paths; a user's module may also define a whole descriptor and be named ``module:DESCRIPTOR``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from framework.diagnosis.effects import Catalogue
    from framework.identification.campaign import Campaign
    from framework.measured.modes import MeasuredModes
    from framework.models.base import StructuralModel
    from framework.models.geometry import GeometryHook


@dataclass(frozen=True)
class StructureDescriptor:
    """A structure (one of its models) and every feature it supports; see the module docstring."""

    name: str
    """Registered name: ``structure.name`` in a config (e.g. ``"lab_frame_3dof"``)."""

    title: str
    """One line saying what it is (listings, error messages, docs)."""

    make_model: Callable[..., StructuralModel]
    """``make_model(**options) -> StructuralModel``; the options are a config's ``structure.options``."""

    measured: Callable[..., MeasuredModes] | None = None
    """``measured(case, **options) -> MeasuredModes``: the structure's measured modes
    (``measured: {builtin: <family>, case: ..., options: {...}}`` in a config)."""

    cases: tuple[str, ...] = ()
    """The cases ``measured`` knows (the first is the default, usually ``"base"``)."""

    family: str = ""
    """Name shared by the models of one physical structure (the 3-DOF and the detailed lab
    frame are both ``"lab_frame"``): configs name its measured data, effect catalogue and
    simulated tests by it. Empty: the descriptor's ``name``."""

    effects: Callable[..., Catalogue] | None = None
    """``effects(**options) -> Catalogue``: candidate physical effects for ``gomu diagnose``
    (:mod:`framework.diagnosis.effects`)."""

    geometry: GeometryHook | None = None
    """``geometry(model, theta, shapes) -> ModelShapes | OpenSeesModel | None``: how to draw the
    modes (:mod:`framework.models.geometry`). None: the model's own ``geometry`` method, or its
    built OpenSees domain, or no geometry (shapes drawn channel by channel)."""

    reproduction: Callable[[Path], list[dict]] | None = None
    """``rows(results_dir) -> [row]``: its rows of docs/reproduction.md (:mod:`framework.report.reproduction`)."""

    tests: Callable[[], Campaign] | None = None
    """``tests() -> Campaign``: its simulated vibration tests for the ``identification`` kind
    (:class:`framework.identification.campaign.Campaign`)."""

    modelling_choices: Callable[..., list[dict]] | None = None
    """``modelling_choices(**options) -> [row]``: the model's documented choices for the report's
    ``choices`` analysis (rows: item, value, origin, reason)."""

    identified: Mapping[str, Callable[[], MeasuredModes]] = field(default_factory=dict)
    """Modes identified from its simulated tests, by case (``measured: {builtin: identified, case: <case>}``)."""

    def __post_init__(self) -> None:
        if not self.name or not callable(self.make_model):
            raise TypeError(f"structure descriptor {self.name!r}: a name and a callable make_model are required")
        if not self.family:
            object.__setattr__(self, "family", self.name)

    def features(self) -> tuple[str, ...]:
        """The optional features it supports, by field name (for listings and tests)."""
        names = ("measured", "effects", "geometry", "reproduction", "tests", "modelling_choices", "identified")
        return tuple(n for n in names if getattr(self, n))

