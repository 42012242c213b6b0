"""The built-in structures, one line each, and the look-ups every feature uses.

Each line is a :class:`~framework.structures.descriptor.StructureDescriptor` defined in its
structure's package (``framework/structures/<name>/descriptor.py``); adding a structure is
its package plus one line in :data:`BUILTIN`. A config names a structure by its ``name``
(``structure: {name: lab_frame_3dof}``), its measured data, effect catalogue and simulated
tests by its ``family`` (``measured: {builtin: lab_frame}``), or a user's own model as
``module:function`` (described by :func:`~framework.structures.references.describe_reference`,
the same descriptor type; no registration needed).

Look-ups: :func:`describe` (a descriptor by name or reference), :func:`make_structure`,
:func:`builtin_measured` (also the ``identified`` data sets and user providers),
:func:`catalogue` (effects for ``gomu diagnose``), :func:`campaign` (simulated tests),
:func:`modelling_choices` and :func:`reproduction_providers` (reports).
"""

from __future__ import annotations

from collections.abc import Callable

from framework.core.errors import InputError
from framework.structures.beam.descriptor import BEAM
from framework.structures.bridge.descriptor import BRIDGE
from framework.structures.descriptor import StructureDescriptor
from framework.structures.frame_two_bay.descriptor import FRAME_TWO_BAY
from framework.structures.lab_frame.descriptor import DETAILED as LAB_FRAME_DETAILED
from framework.structures.lab_frame.descriptor import THREE_DOF as LAB_FRAME_3DOF
from framework.structures.references import check_reference, describe_reference, resolve
from framework.structures.smu.descriptor import FOOTBRIDGE, FOUR_STORY

#: the built-in structures, in report order (docs/reproduction.md follows it)
BUILTIN: tuple[StructureDescriptor, ...] = (
    LAB_FRAME_3DOF,
    LAB_FRAME_DETAILED,
    BRIDGE,
    BEAM,
    FOUR_STORY,
    FOOTBRIDGE,
    FRAME_TWO_BAY,
)

#: the name of the data sets identified from simulated tests (``measured: {builtin: identified, case: ...}``)
IDENTIFIED = "identified"

#: structure name -> descriptor
STRUCTURES: dict[str, StructureDescriptor] = {}
#: measured data set name (a family) -> the descriptor providing it
MEASUREMENTS: dict[str, StructureDescriptor] = {}
#: effect catalogue name (a family) -> the descriptor providing it
CATALOGUES: dict[str, StructureDescriptor] = {}
#: simulated-test structure name (a family) -> the descriptor providing the campaign
CAMPAIGNS: dict[str, StructureDescriptor] = {}
#: identified data set case -> its provider
IDENTIFIED_CASES: dict[str, Callable] = {}


def _index() -> None:
    """Fill the look-up tables from :data:`BUILTIN` (a family's feature: its first descriptor with it)."""
    tables = {"measured": MEASUREMENTS, "effects": CATALOGUES, "tests": CAMPAIGNS}
    for table in (STRUCTURES, IDENTIFIED_CASES, *tables.values()):
        table.clear()
    for d in BUILTIN:
        if d.name in STRUCTURES:
            raise ValueError(f"structure {d.name!r} is registered twice")
        STRUCTURES[d.name] = d
        for hook, table in tables.items():
            if getattr(d, hook):
                table.setdefault(d.family, d)
        IDENTIFIED_CASES.update(d.identified)


_index()


def is_reference(name: str) -> bool:
    """True for a ``module:function`` reference to user code (not a built-in name)."""
    return isinstance(name, str) and ":" in name and name not in STRUCTURES and name not in MEASUREMENTS


def describe(name: str) -> StructureDescriptor:
    """The descriptor of structure ``name``: a built-in name or a user's 'module:function'."""
    if name in STRUCTURES:
        return STRUCTURES[name]
    check_reference(name, f"structure.name={name!r}")  # an unknown name: "neither a built-in name nor ..."
    return describe_reference(name)


def make_structure(name: str, **options):
    """Build structure ``name`` (built-in name or 'module:function') with options."""
    factory = describe(name).make_model
    try:
        return factory(**options)
    except InputError:
        raise
    except TypeError as exc:
        raise InputError(f"structure {name!r}: bad options {sorted(options)}: {exc}") from None
    except Exception as exc:  # a user's factory can raise anything: one line, not a traceback
        raise InputError(f"structure {name!r}: building the model failed: {type(exc).__name__}: {exc}") from None


def _identified(case: str, **options):
    if options:
        raise TypeError(f"identified data sets take no options, got {sorted(options)}")
    if case not in IDENTIFIED_CASES:
        raise InputError(f"identified measured data: unknown case {case!r}; known: {list(IDENTIFIED_CASES)}")
    return IDENTIFIED_CASES[case]()


def builtin_measured(name: str, case: str = "base", **options):
    """Measured data set ``name`` (a structure family, ``identified``, or a user's 'module:function'
    or 'module:DESCRIPTOR') for ``case``; ``options`` go to the provider as keywords (e.g. the lab
    frame's ``congruence``)."""
    if name == IDENTIFIED:
        provider = _identified
    elif name in MEASUREMENTS:
        provider = MEASUREMENTS[name].measured
    elif ":" in name:  # a user's data provider, or a user's descriptor with measured data
        provider = resolve(name, f"measured.builtin={name!r}")
        if isinstance(provider, StructureDescriptor):
            if provider.measured is None:
                raise InputError(f"measured.builtin={name!r}: structure {provider.name!r} has no measured data")
            provider = provider.measured
    else:
        raise InputError(f"measured.builtin={name!r} unknown; known: {sorted([*MEASUREMENTS, IDENTIFIED])}")
    try:
        return provider(case, **options)
    except InputError:
        raise
    except TypeError as exc:
        if options:
            raise InputError(f"measured.builtin={name!r}: bad options {sorted(options)}: {exc}") from None
        raise InputError(f"measured.builtin={name!r}: case {case!r}: {type(exc).__name__}: {exc}") from None
    except Exception as exc:
        raise InputError(f"measured.builtin={name!r}: case {case!r}: {type(exc).__name__}: {exc}") from None


def catalogue(name: str, **options):
    """The effect catalogue of structure ``name`` (a key of CATALOGUES or a user's 'module:function')."""
    if name in CATALOGUES:
        hook = CATALOGUES[name].effects
    elif ":" in name:
        hook = describe_reference(name).effects
    else:
        raise InputError(f"structure {name!r} has no effect catalogue; known: {sorted(CATALOGUES)}")
    try:
        return hook(**options)
    except InputError:
        raise
    except TypeError as exc:
        raise InputError(f"structure {name!r}: bad catalogue options {sorted(options)}: {exc}") from None
    except Exception as exc:  # a user's build can raise anything: one line naming module and error
        raise InputError(f"structure {name!r}: {name} failed: {type(exc).__name__}: {exc}") from None


def campaign(name: str):
    """The simulated vibration tests of structure ``name`` (a key of CAMPAIGNS)."""
    if name not in CAMPAIGNS:
        raise InputError(f"structure {name!r} has no simulated tests; known: {sorted(CAMPAIGNS)}")
    return CAMPAIGNS[name].tests()


def modelling_choices(name: str) -> Callable[..., list[dict]]:
    """The ``modelling_choices(**options)`` of structure ``name`` (a built-in, or a user's
    'module:DESCRIPTOR'), for the report's choices analysis."""
    if name not in STRUCTURES and not (isinstance(name, str) and ":" in name):
        raise InputError(f"report.choices.structure.name: {name!r} is not a built-in structure")
    function = describe(name).modelling_choices
    if function is None:
        raise InputError(f"report.choices.structure.name: structure {name!r} documents no modelling choices")
    return function


def reproduction_providers() -> list[Callable]:
    """The reproduction-report providers ``rows(results_dir)`` of the built-in structures, in order."""
    return [d.reproduction for d in BUILTIN if d.reproduction is not None]
