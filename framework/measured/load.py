"""Test-data exchange: measured modes from UFF files and pyOMA2 results, model modes to UFF.

- :func:`load_measured`: measured modes from a file by suffix: ``.unv``/``.uff`` through
  :func:`read_uff_modes` with a mapping file, anything else through
  :func:`framework.measured.modes.load` (YAML/CSV).
- :func:`read_uff_modes`, :func:`write_uff_modes`: :mod:`framework.measured.uff`.
- :func:`from_pyoma2`: :mod:`framework.measured.pyoma2`.
- mapping files (test node + direction or OMA channel -> model DOF): :mod:`framework.measured.mapping`.

Documentation: docs/exchange.md.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from framework.core.errors import InputError
from framework.measured.mapping import DofMapping, as_mapping, load_mapping, parse_mapping
from framework.measured.modes import MeasuredModes
from framework.measured.pyoma2 import from_pyoma2
from framework.measured.uff import read_uff_modes, write_uff_modes

#: File suffixes read as Universal File Format.
UFF_SUFFIXES = (".unv", ".uff")

__all__ = [
    "UFF_SUFFIXES",
    "DofMapping",
    "as_mapping",
    "from_pyoma2",
    "load_mapping",
    "load_measured",
    "parse_mapping",
    "read_uff_modes",
    "write_uff_modes",
]


def load_measured(path: str | Path, mapping: DofMapping | Mapping | str | Path | None = None) -> MeasuredModes:
    """Measured modes from ``path``: UFF (.unv/.uff) with ``mapping``, else YAML/CSV.

    A mapping is meaningful only for UFF files; giving one with another format is an error.
    """
    from framework.measured import modes as measurements

    path = Path(path)
    if path.suffix.lower() in UFF_SUFFIXES:
        return read_uff_modes(path, mapping)
    if mapping is not None:
        suffixes = ", ".join(UFF_SUFFIXES)
        raise InputError(f"{path}: a mapping applies to UFF files ({suffixes}) only, not {path.suffix!r}")
    return measurements.load(path)
