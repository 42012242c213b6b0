"""Measured modes from a pyOMA2 result (after modal parameter extraction, ``mpe``).

pyOMA2 results (SSIResult, FDDResult, EFDDResult, pLSCFResult, ClusteringResult,
MsPoserResult, ...) carry natural frequencies ``Fn`` (Hz, (m,)), complex mode shapes
``Phi`` ((n_channels, m)) and, for all but FDD, damping ratios ``Xi`` ((m,)); with
uncertainty estimation also ``Fn_std`` (standard deviation, Hz). The ``channels``
section of a mapping file names the model DOF of each used channel (0-based index, or a
name from ``channel_names``, e.g. the ``sens_names`` of a pyOMA2 geometry):
model value = sign x channel value. Shapes are made real with
:func:`framework.measured.complex_shapes.real_mode_shape` after the mapping; the MAC loss of each
mode is logged and kept in ``meta["complex_to_real_mac_loss"]``.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from framework.core.errors import InputError
from framework.measured.complex_shapes import real_mode_shape
from framework.measured.mapping import DofMapping, as_mapping
from framework.measured.modes import MeasuredModes

log = logging.getLogger(__name__)


def _result_of(obj):
    """The result object itself, or the ``.result`` of a pyOMA2 algorithm."""
    if getattr(obj, "Fn", None) is None and getattr(getattr(obj, "result", None), "Fn", None) is not None:
        return obj.result
    return obj


def _array(result, name: str, source: str, dtype=float) -> np.ndarray | None:
    value = getattr(result, name, None)
    if value is None:
        return None
    try:
        return np.asarray(value, dtype=dtype)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{source}: {name} is not numeric: {value!r}") from exc


def from_pyoma2(
    result_object,
    mapping: DofMapping | Mapping | str | Path,
    channel_names: Sequence[str] | None = None,
    *,
    name: str = "pyoma2",
) -> MeasuredModes:
    """MeasuredModes (frequencies, real shapes at the mapped model DOFs, damping) from a pyOMA2 result.

    result_object: a pyOMA2 result or the algorithm holding it (``alg.result``) after
    ``mpe``. mapping: a mapping with a ``channels`` section (see :mod:`framework.measured.mapping`).
    """
    result = _result_of(result_object)
    source = f"pyOMA2 {type(result).__name__}"
    mapping = as_mapping(mapping)
    if mapping is None or not mapping.channels:
        where = mapping.source if mapping is not None else source
        raise InputError(f"{where}: no 'channels' section (channel -> model DOF) to read a pyOMA2 result")
    fn = _array(result, "Fn", source)
    phi = _array(result, "Phi", source, dtype=complex)
    if fn is None or phi is None:
        raise InputError(f"{source}: Fn and Phi are empty; run the algorithm and its mpe(...) first")
    fn = fn.reshape(-1)
    if phi.ndim != 2 or phi.shape[1] != fn.size:
        raise InputError(f"{source}: Phi has shape {phi.shape}, expected (n_channels, {fn.size} modes)")
    if not np.all(np.isfinite(fn)) or not np.all(np.isfinite(phi)):
        raise InputError(f"{source}: Fn or Phi has NaN/inf (a selected frequency without a pole?): Fn {fn.tolist()}")
    n_channels = phi.shape[0]
    names = list(channel_names) if channel_names is not None else None
    if names is not None and len(names) != n_channels:
        raise InputError(f"{source}: {len(names)} channel names for {n_channels} channels")
    rows, dofs = [], []
    for entry in mapping.channels:
        where = f"{mapping.source}: channels[{entry.channel!r}]"
        if isinstance(entry.channel, int):
            if entry.channel >= n_channels:
                raise InputError(f"{where}: channel index out of range; {source} has {n_channels} channels (0-based)")
            index = entry.channel
        else:
            if names is None or entry.channel not in names:
                raise InputError(f"{where}: unknown channel name; known: {names}")
            index = names.index(entry.channel)
        rows.append(entry.sign * phi[index])
        dofs.append(entry.dof)
    unused = n_channels - len(rows)
    if unused:
        log.info("%s: %d channels not in the mapping were ignored", source, unused)
    shapes = np.array(rows)
    real = np.empty(shapes.shape)
    losses = []
    for j in range(fn.size):
        real[:, j], loss = real_mode_shape(shapes[:, j])
        losses.append(loss)
        level = logging.WARNING if loss > 0.05 else logging.INFO
        log.log(level, "%s: mode %d (%.4g Hz) complex shape made real, MAC loss %.3g", source, j + 1, fn[j], loss)
    xi = _array(result, "Xi", source)
    fn_std = _array(result, "Fn_std", source)
    if fn_std is not None and (fn_std.shape != fn.shape or not np.all(np.isfinite(fn_std))):
        fn_std = None
    return MeasuredModes(
        frequencies_hz=fn,
        dofs=tuple(dofs),
        shapes=real,
        damping_ratio=None if xi is None else xi.reshape(-1),
        frequency_std_hz=fn_std,
        name=name,
        source=source,
        meta={"format": "pyoma2", "result": type(result).__name__, "complex_to_real_mac_loss": losses},
    )
