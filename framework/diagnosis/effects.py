"""Candidate physical effects and per-structure catalogues.

An :class:`Effect` is a named physical enrichment of a structural model with its own
parameters (bounds, and the value at which the effect vanishes, ``initial``) and,
optionally, discrete *variants* (e.g. the element where a stiffness loss sits). A
:class:`Catalogue` knows a structure's base (always calibrated) parameters, its candidate
effects, and how to build the model with any set of active effects:

    catalogue.model({"effect": "variant", ...}) -> StructuralModel

whose ``parameters`` are the base parameters followed by the active effects' parameters.
Parameters of inactive effects do not exist in that model (they keep their null value).
A structure's catalogue lives in its package and reaches the diagnosis through its
descriptor (``StructureDescriptor.effects``, looked up by
:func:`framework.structures.registry.catalogue`); a model without hand-written effects gets
:func:`catalogue_of_model` (generated candidates, :mod:`framework.diagnosis.auto`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from framework.core.errors import InputError
from framework.core.parameters import Parameter, ParameterSet
from framework.models.base import ModalResult, StructuralModel

Active = Mapping[str, str]


@dataclass(frozen=True)
class Effect:
    """A candidate enrichment: name, parameters (initial = no effect), discrete variants.

    hidden_values: {parameter: (low, high)} range from which the data generator draws the
    effect's true values (a clearly present effect); hidden_variants: variants it may pick.
    """

    name: str
    description: str
    parameters: tuple[Parameter, ...] = ()
    variants: tuple[str, ...] = ("",)
    hidden_values: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    hidden_variants: tuple[str, ...] | None = None
    #: {parameter: +1 or -1}: the sign of (value - null) that the effect's physics implies;
    #: a fit of the other sign is flagged (parameters whose bounds allow both signs)
    expected_sign: Mapping[str, int] = field(default_factory=dict)

    @property
    def n_parameters(self) -> int:
        return len(self.parameters)

    @property
    def parameter_names(self) -> list[str]:
        return [p.name for p in self.parameters]


@dataclass(frozen=True)
class Catalogue:
    """A structure's base parameters, candidate effects and model factory.

    factory(active, **options) -> StructuralModel with parameters base + active effects'.
    select_modes(result, n_modes) -> indices of the modes a test would measure (used by
    the data generator; default: the lowest n_modes); mode_labels: their labels (or
    label_modes(result, indices) -> labels, computed from the truth's modes);
    settings: recommended workflow settings for this structure (e.g. a frequency window).
    """

    structure: str
    base_parameters: ParameterSet
    effects: Mapping[str, Effect]
    factory: Callable[..., StructuralModel]
    n_measured_modes: int
    options: Mapping[str, object] = field(default_factory=dict)
    select_modes: Callable[[ModalResult, int], np.ndarray] | None = None
    description: str = ""
    mode_labels: tuple[str, ...] = ()
    settings: Mapping[str, object] = field(default_factory=dict)
    label_modes: Callable[[ModalResult, np.ndarray], tuple[str, ...]] | None = None
    #: the effects a diagnosis tries (None: every effect); the others still build (hidden data)
    candidates: tuple[str, ...] | None = None
    #: names of the effects generated from the model (:mod:`framework.diagnosis.auto`)
    generated: tuple[str, ...] = ()

    def candidate_effects(self) -> dict[str, Effect]:
        """The effects a diagnosis tries, in catalogue order."""
        if self.candidates is None:
            return dict(self.effects)
        return {k: v for k, v in self.effects.items() if k in self.candidates}

    def effect(self, name: str) -> Effect:
        if name not in self.effects:
            raise InputError(f"{self.structure}: effect {name!r} unknown; catalogue: {sorted(self.effects)}")
        return self.effects[name]

    def check_active(self, active: Active) -> dict[str, str]:
        out = {}
        for name, variant in dict(active).items():
            eff = self.effect(name)
            variant = "" if variant is None else str(variant)
            if variant not in eff.variants:
                raise InputError(
                    f"{self.structure}: effect {name!r} variant {variant!r} unknown; variants: {list(eff.variants)}"
                )
            out[name] = variant
        return out

    def parameters(self, active: Active) -> ParameterSet:
        """Base parameters followed by the active effects' parameters."""
        items = list(self.base_parameters)
        for name in self.check_active(active):
            items.extend(self.effect(name).parameters)
        return ParameterSet(items)

    def model(self, active: Active | None = None) -> StructuralModel:
        """The model with ``active`` effects ({name: variant})."""
        active = self.check_active(active or {})
        return self.factory(active, **dict(self.options))

    def modes_to_measure(self, result: ModalResult, n_modes: int | None = None) -> np.ndarray:
        n = n_modes or self.n_measured_modes
        if self.select_modes is not None:
            return np.asarray(self.select_modes(result, n), dtype=int)
        if result.n_modes < n:
            raise InputError(f"{self.structure}: truth model has {result.n_modes} modes, {n} requested")
        return np.arange(n)


def as_catalogue(out, structure: str, source: str = "") -> Catalogue:
    """What a structure's catalogue function returned, as a Catalogue: a Catalogue as is, an
    OpenSees model as a catalogue without hand-written effects (``candidates: auto``)."""
    if isinstance(out, Catalogue):
        return out
    from framework.models.opensees import OpenSeesModel

    if isinstance(out, OpenSeesModel):  # a model without hand-written effects (candidates: auto)
        return catalogue_of_model(out, structure=structure)
    raise InputError(f"structure {structure!r}: {source or structure} returned {type(out).__name__}, "
                     "not a Catalogue or OpenSeesModel")


def catalogue_of_model(model, structure: str = "user_model", n_measured_modes: int | None = None) -> Catalogue:
    """A catalogue without hand-written effects whose model under test is ``model``."""

    def factory(active, **_):
        if active:
            raise InputError(f"{structure}: no hand-written effects; unknown {sorted(active)}")
        return model

    return Catalogue(structure, model.parameters, {}, factory, n_measured_modes or model.n_modes,
                     description=f"{model.name}")  # fmt: skip
