"""Cable-stayed pedestrian bridge (SPEC section 6): OpenSeesPy model, modes, measured data.

``make_model(cable_elements=4, fast=True, ...)`` builds the model, ``measured(case)`` gives
the measured modes; the structure is registered as ``bridge`` in
:mod:`framework.structures.registry` (its descriptor: :mod:`.descriptor`). Model notes: docs/bridge.md.

Modules, one job each (imports only go down this list, no cycles):

- :mod:`.section`: the deck's cross-section readings, their composite constants and masses;
- :mod:`.geometry`: dimensions, member sections, bearings, node numbering, sensor DOFs,
  :class:`~.geometry.BridgeInfo`;
- :mod:`.parameters`: the six updating parameters (ratios, bounds 0.6-1.3);
- :mod:`.data`: published values (measured and design-model frequencies, damping, labels);
- :mod:`.build`: the OpenSeesPy build, its gravity analysis and cable tensions;
- :mod:`.modes`: mode classification by kinetic energy, deck-mode selection, pairing by type;
- :mod:`.fast`: the fast eigen path (OpenSees gravity, numpy/scipy eigen solution);
- :mod:`.model`: :func:`make_model`, plain or fast path;
- :mod:`.choices`: the model's modelling choices as table rows (:func:`modelling_choices`);
- :mod:`.reference`: :func:`measured`, with reference shapes from the initial model;
- :mod:`.effects`: the effect catalogue of ``gomu diagnose``;
- :mod:`.vibration_tests` and :mod:`.campaign`: the simulated shaker and jumping tests and the
  modes identified from them;
- :mod:`.reproduction`: the bridge's rows of docs/reproduction.md;
- :mod:`.descriptor`: :data:`~.descriptor.BRIDGE`, every feature above for the registry
  (nothing in the package imports it, nor this face).
"""

from framework.structures.bridge.choices import modelling_choices
from framework.structures.bridge.data import (
    DESIGN_MODEL_HZ,
    MEASURED_DAMPING,
    MEASURED_HZ,
    MEASURED_LABELS,
    MEASURED_PEAK_HZ,
    MEASURED_TYPES,
)
from framework.structures.bridge.geometry import DESIGN_TENSION_N
from framework.structures.bridge.model import make_model
from framework.structures.bridge.modes import pair_by_type
from framework.structures.bridge.parameters import PARAMETER_NAMES, bridge_parameters
from framework.structures.bridge.reference import measured
from framework.structures.bridge.section import composite_constants, deck_mass_per_m, mass_items

__all__ = [
    "DESIGN_MODEL_HZ",
    "DESIGN_TENSION_N",
    "MEASURED_DAMPING",
    "MEASURED_HZ",
    "MEASURED_LABELS",
    "MEASURED_PEAK_HZ",
    "MEASURED_TYPES",
    "PARAMETER_NAMES",
    "bridge_parameters",
    "composite_constants",
    "deck_mass_per_m",
    "make_model",
    "mass_items",
    "measured",
    "modelling_choices",
    "pair_by_type",
]
