"""The modelling and method choices of a study as a table (``choices.csv``), from its config.

Asked for in the config's ``report``::

    report:
      choices:
        structure: {name: bridge, variant: cables_4}    # the structure's own documented choices
        items:                                          # the study's own (methods, data)
          - {item: SM method, value: pseudo-inverse iteration, origin: source-given, reason: SPEC 4}

Table ``choices``: study, item, value, origin ("source-given" or "our assumption"), reason.
A structure documents its choices with ``modelling_choices(**options)`` in its descriptor
(e.g. the bridge's, :func:`framework.structures.bridge.choices.modelling_choices`); the study
layer passes that function in as ``modelling_choices`` (this module imports no structure).
The options are ``structure.options`` if given, else read from the study's tables for
``variant`` (the ``analysis`` kind writes every scalar structure option as a column), else
the defaults.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from pathlib import Path

import pandas as pd

from framework.core.errors import InputError

COLUMNS = ("study", "item", "value", "origin", "reason")
ORIGINS = ("source-given", "our assumption")


def _options_from_tables(tables: dict[str, pd.DataFrame], function, variant: str | None) -> dict:
    names = [p for p in inspect.signature(function).parameters if p != "_"]
    first = next((t for t in tables.values() if t is not None and not t.empty and "variant" in t), None)
    if first is None:
        return {}
    if variant is None and first["variant"].nunique() > 1:
        raise InputError(f"report.choices.structure: the study has several variants "
                         f"({sorted(first['variant'].unique())}); name one as 'variant'")
    rows = first[first["variant"] == variant] if variant is not None else first
    if rows.empty:
        raise InputError(f"report.choices.structure.variant: no rows of variant {variant!r}")
    out = {}
    for name in names:
        if name in rows and rows[name].notna().any():
            values = rows[name].dropna().unique()
            if len(values) > 1 or rows[name].isna().any():  # a missing value is the default: another value
                raise InputError(f"report.choices.structure: option {name!r} differs between the rows "
                                 f"({list(values)}); name a variant")
            value = values[0]
            out[name] = value.item() if hasattr(value, "item") else value
    return out


def tables(tables: dict[str, pd.DataFrame], structure: dict | None = None, items: list | None = None,
           modelling_choices: Callable[..., list[dict]] | None = None, **_) -> dict[str, pd.DataFrame]:
    """The ``choices`` table; ``modelling_choices``: the named structure's (given by the study layer)."""
    rows = []
    if structure:
        name = structure.get("name")
        if modelling_choices is None:
            raise InputError(f"report.choices.structure.name: structure {name!r} documents no modelling choices")
        options = structure.get("options")
        if options is None:
            options = _options_from_tables(tables, modelling_choices, structure.get("variant"))
        rows += modelling_choices(**options)
    for i, item in enumerate(items or []):
        missing = [k for k in COLUMNS[1:] if k not in item]
        if missing:
            raise InputError(f"report.choices.items[{i}]: missing {missing}")
        rows.append({k: str(item[k]) for k in COLUMNS[1:]})
    bad = [r["origin"] for r in rows if r["origin"] not in ORIGINS]
    if bad:
        raise InputError(f"report.choices: origin must be one of {list(ORIGINS)}, got {bad}")
    if not rows:
        return {}
    study = next((str(t["study"].iloc[0]) for t in tables.values()
                  if t is not None and not t.empty and "study" in t), "")
    return {"choices": pd.DataFrame([{"study": study, **r} for r in rows], columns=list(COLUMNS))}


def figures(tables: dict[str, pd.DataFrame], out_dir: Path, **_) -> list[Path]:
    return []
