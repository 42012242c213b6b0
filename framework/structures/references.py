"""A user's code named in a config as ``module:function``: checks, import, and its descriptor.

Trust model: a config that names code is code. Only structure factories, catalogues and
data providers are resolved this way, and only to a function or class defined in the named
module (``os:system`` names a function of ``posix`` and is refused), or to a
:class:`~framework.structures.descriptor.StructureDescriptor` the module defines; modules of
the Python standard library are refused outright. ``gomu validate`` checks the form only
(:func:`check_reference`), importing nothing.
"""

from __future__ import annotations

import importlib
import sys

from framework.core.errors import InputError
from framework.structures.descriptor import StructureDescriptor


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
    """Import ``module:function`` and return the function (or descriptor); errors name the entry."""
    module, attr = check_reference(path, what)
    try:
        obj = getattr(importlib.import_module(module), attr)
    except ImportError as exc:
        raise InputError(f"{what}: cannot import module {module!r}: {exc}") from None
    except AttributeError:
        raise InputError(f"{what}: module {module!r} has no {attr!r}") from None
    except Exception as exc:  # importing user code ran it and it failed
        raise InputError(f"{what}: importing {module!r} failed: {type(exc).__name__}: {exc}") from None
    if isinstance(obj, StructureDescriptor):
        return obj
    defined_in = getattr(obj, "__module__", None) or ""
    if not callable(obj) or not (defined_in == module or defined_in.startswith(module + ".")):
        raise InputError(f"{what}: {path!r} is not a function or class defined in module {module!r}")
    return obj


def describe_reference(path: str) -> StructureDescriptor:
    """The descriptor of a user's ``module:function`` (or ``module:DESCRIPTOR``).

    The function may return a :class:`~framework.models.base.StructuralModel` or an effect
    :class:`~framework.diagnosis.effects.Catalogue` (whose model under test is then the model);
    its effects are that catalogue, or for an OpenSees model a catalogue without hand-written
    effects (generated candidates, ``candidates: auto``). Its geometry is the model's own (its
    ``geometry`` method or its built OpenSees domain). Imports the module (trust rules above).
    """
    target = resolve(path, f"structure.name={path!r}")
    if isinstance(target, StructureDescriptor):
        return target

    def make_model(**options):
        from framework.diagnosis.effects import Catalogue

        out = target(**options)
        return out.model({}) if isinstance(out, Catalogue) else out

    def effects(**options):
        from framework.diagnosis.effects import as_catalogue

        return as_catalogue(target(**options), structure=path, source=path)

    return StructureDescriptor(name=path, title=f"user model {path}", make_model=make_model, effects=effects)
