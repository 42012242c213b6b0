"""Built-in structures and measured data sets, by name.

A structure module exposes ``make_model(**options) -> StructuralModel`` and
``measured(case="base") -> MeasuredModes``. Entries are import paths so that importing
the registry stays cheap (OpenSees is only loaded when an OpenSees structure is used).
A user's own model is given in a config as ``structure: {name: "my_pkg.my_mod:make_model"}``.
"""

from __future__ import annotations

import importlib
import sys

from framework.core.errors import InputError

STRUCTURES: dict[str, str] = {
    "lab_frame_3dof": "framework.structures.lab_frame.model:make_model",
    "lab_frame_detailed": "framework.structures.lab_frame.detailed:make_model",
    "bridge": "framework.structures.bridge:make_model",
    "beam": "framework.structures.beam.model:make_model",
    "four_story": "framework.structures.smu.model:make_four_story",
    "footbridge": "framework.structures.smu.model:make_footbridge",
}

MEASUREMENTS: dict[str, str] = {
    "lab_frame": "framework.structures.lab_frame.model:measured",
    "bridge": "framework.structures.bridge:measured",
    "beam": "framework.structures.beam.model:measured",
    "identified": "framework.identification.datasets:measured",
    "four_story": "framework.structures.smu.model:four_story_measured",
    "footbridge": "framework.structures.smu.model:footbridge_measured",
}


def is_reference(name: str) -> bool:
    """True for a ``module:function`` reference to user code (not a built-in name)."""
    return isinstance(name, str) and ":" in name and name not in STRUCTURES and name not in MEASUREMENTS


def check_reference(path: str, what: str) -> tuple[str, str]:
    """The checks of :func:`resolve` that import nothing: ``module:function`` form, module not
    of the standard library. Returns (module, function name)."""
    if not isinstance(path, str) or ":" not in path:
        raise InputError(f"{what}: {path!r} is neither a built-in name nor 'module:function'")
    module, attr = path.split(":", 1)
    top = module.split(".")[0]
    if not module or not attr or top in sys.stdlib_module_names:
        raise InputError(f"{what}: {path!r} is not a structure or data provider of a user module")
    return module, attr


def resolve(path: str, what: str):
    """Import ``module:function`` and return the function; errors name the entry.

    Trust model: a config that names code is code. Only structure factories and data
    providers are resolved this way, and only to a function or class defined in the named
    module (``os:system`` names a function of ``posix`` and is refused); modules of the
    Python standard library are refused outright.
    """
    module, attr = check_reference(path, what)
    try:
        obj = getattr(importlib.import_module(module), attr)
    except ImportError as exc:
        raise InputError(f"{what}: cannot import module {module!r}: {exc}") from None
    except AttributeError:
        raise InputError(f"{what}: module {module!r} has no {attr!r}") from None
    except Exception as exc:  # importing user code ran it and it failed
        raise InputError(f"{what}: importing {module!r} failed: {type(exc).__name__}: {exc}") from None
    defined_in = getattr(obj, "__module__", None) or ""
    if not callable(obj) or not (defined_in == module or defined_in.startswith(module + ".")):
        raise InputError(f"{what}: {path!r} is not a function or class defined in module {module!r}")
    return obj


def make_structure(name: str, **options):
    """Build structure ``name`` (built-in name or 'module:function') with options."""
    factory = resolve(STRUCTURES.get(name, name), f"structure.name={name!r}")
    try:
        return factory(**options)
    except InputError:
        raise
    except TypeError as exc:
        raise InputError(f"structure {name!r}: bad options {sorted(options)}: {exc}") from None
    except Exception as exc:  # a user's factory can raise anything: one line, not a traceback
        raise InputError(f"structure {name!r}: building the model failed: {type(exc).__name__}: {exc}") from None


def builtin_measured(name: str, case: str = "base", **options):
    """Measured data set ``name`` (built-in name or 'module:function') for ``case``;
    ``options`` go to the provider as keywords (e.g. the lab frame's ``congruence``)."""
    if name not in MEASUREMENTS and ":" not in name:
        raise InputError(f"measured.builtin={name!r} unknown; known: {sorted(MEASUREMENTS)}")
    provider = resolve(MEASUREMENTS.get(name, name), f"measured.builtin={name!r}")
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
