"""Run kinds: what one run of a study does. A static registry of :class:`~framework.study.kinds.base.Kind`
objects, one line per kind.

Each kind is a module of this package that builds one ``KIND`` object (its schema, tables,
``plan_runs``, ``run`` and optional hooks; :mod:`framework.study.kinds.base` says what each
field means and what the engine does the same way for every kind: failure rows, the runner and
isolation of model evaluations, preflight, report options, mode shapes). A new kind is a module
``framework/study/kinds/<name>.py`` with its ``KIND`` and one line in :data:`KINDS`.
"""

from __future__ import annotations

from framework.core.errors import InputError
from framework.study.kinds import analysis, damage, diagnose, identification, posterior, updating
from framework.study.kinds.base import Kind

KINDS: dict[str, Kind] = {kind.name: kind for kind in (
    updating.KIND,
    identification.KIND,
    analysis.KIND,
    diagnose.KIND,
    posterior.KIND,
    damage.KIND,
)}


def get_kind(name: str) -> Kind:
    """The run kind ``name``."""
    if not isinstance(name, str) or name not in KINDS:
        raise InputError(f"kind: unknown run kind {name!r}; known: {sorted(KINDS)}")
    return KINDS[name]
