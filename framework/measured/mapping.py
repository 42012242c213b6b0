"""Mapping of test sensors to model DOFs: the small YAML file next to a test-data file.

::

    dofs:                  # UFF: test node + direction -> model DOF label
      "101+x": floor1_x    # model floor1_x = +(x component of node 101)
      "102-y": floor2_y    # model floor2_y = -(y component of node 102)
    channels:              # pyOMA2: channel (0-based index or name) -> model DOF label
      0: floor1_x
      1: -floor2_y         # a leading '-' flips the sign (sensor against the model axis)

A test DOF is ``<node><sign><axis>``: node a positive integer, sign ``+`` or ``-``, axis
one of x, y, z (translations) or rx, ry, rz (rotations), in the global axes of the test
geometry. The sign says which way the model DOF points in test axes:
``model value = sign x test value``. Each test DOF, channel and model DOF may appear
once. Parsed by hand (a few lines of validation on top of PyYAML) because the format is
ours; every error is one line naming the file, the key and the value.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from framework.core.errors import InputError

#: Components of a UFF dataset-55 node record, in file order (3 or 6 values per node).
AXES = ("x", "y", "z", "rx", "ry", "rz")
ROTATIONS = frozenset({"rx", "ry", "rz"})
#: UFF node labels are written in I10 fields.
MAX_NODE = 2**31 - 1

_TEST_DOF = re.compile(r"^\s*(\d{1,10})\s*([+-])\s*(rx|ry|rz|x|y|z)\s*$", re.IGNORECASE | re.ASCII)
_TOP_KEYS = ("dofs", "channels")


@dataclass(frozen=True, order=True)
class SensorDof:
    """One test DOF: node number, axis (x..rz) and sign (+1 / -1)."""

    node: int
    axis: str
    sign: int = 1

    @property
    def label(self) -> str:
        return f"{self.node}{'+' if self.sign > 0 else '-'}{self.axis}"

    @property
    def component(self) -> int:
        """0-based index of the axis in a node record (x, y, z, rx, ry, rz)."""
        return AXES.index(self.axis)


@dataclass(frozen=True)
class ChannelDof:
    """One OMA channel (0-based index or name) mapped to a model DOF with a sign."""

    channel: int | str
    dof: str
    sign: int = 1


@dataclass(frozen=True)
class DofMapping:
    """Parsed mapping file: UFF test DOFs and OMA channels, each paired with a model DOF label."""

    dofs: tuple[tuple[SensorDof, str], ...] = ()
    channels: tuple[ChannelDof, ...] = ()
    source: str = "<mapping>"

    @property
    def model_dofs(self) -> tuple[str, ...]:
        return tuple(d for _, d in self.dofs)


def parse_sensor_dof(text: object, where: str) -> SensorDof:
    """'101+x' -> SensorDof(101, 'x', +1); anything else is an InputError naming ``where``."""
    if isinstance(text, bool) or not isinstance(text, str):
        raise InputError(f"{where}: test DOF {text!r} must be a string like '101+x' (node, sign, axis)")
    match = _TEST_DOF.match(text)
    if match is None:
        raise InputError(
            f"{where}: test DOF {text!r} is not <node><+|-><axis> with axis in {list(AXES)}, e.g. '101+x'"
        )
    node = int(match.group(1))
    if not 1 <= node <= MAX_NODE:
        raise InputError(f"{where}: test DOF {text!r}: node must be in 1..{MAX_NODE}, got {node}")
    return SensorDof(node, match.group(3).lower(), 1 if match.group(2) == "+" else -1)


def _model_dof(value: object, where: str) -> str:
    if isinstance(value, bool) or not isinstance(value, str) or not value.strip():
        raise InputError(f"{where}: model DOF label must be a non-empty string, got {value!r} (quote it in YAML)")
    if value != value.strip() or any(c in value for c in "\r\n\t"):
        raise InputError(f"{where}: model DOF label {value!r} has surrounding or control whitespace")
    return value


def parse_mapping(data: object, source: str = "<mapping>") -> DofMapping:
    """Validate the YAML structure of the module docstring into a :class:`DofMapping`."""
    if not isinstance(data, Mapping):
        raise InputError(f"{source}: expected a mapping with 'dofs' and/or 'channels', got {type(data).__name__}")
    unknown = [k for k in data if k not in _TOP_KEYS]
    if unknown:
        raise InputError(f"{source}: unknown key(s) {unknown!r}; allowed: {list(_TOP_KEYS)}")
    if not any(data.get(k) for k in _TOP_KEYS):
        raise InputError(f"{source}: give a non-empty 'dofs' (UFF) or 'channels' (pyOMA2) mapping")
    dofs = _parse_dofs(data.get("dofs"), source)
    channels = _parse_channels(data.get("channels"), source)
    return DofMapping(dofs, channels, source)


def _section(value: object, name: str, source: str) -> Mapping:
    if value is None:
        return {}
    if not isinstance(value, Mapping):
        raise InputError(f"{source}: '{name}' must be a mapping of key: model DOF, got {value!r}")
    return value


def _parse_dofs(value: object, source: str) -> tuple[tuple[SensorDof, str], ...]:
    out: list[tuple[SensorDof, str]] = []
    seen_test: dict[tuple[int, str], str] = {}
    seen_model: dict[str, str] = {}
    for key, target in _section(value, "dofs", source).items():
        where = f"{source}: dofs[{key!r}]"
        dof = parse_sensor_dof(key, where)
        label = _model_dof(target, where)
        if (dof.node, dof.axis) in seen_test:
            first = seen_test[dof.node, dof.axis]
            raise InputError(f"{where}: node {dof.node} axis {dof.axis} already mapped by {first!r}")
        if label in seen_model:
            raise InputError(f"{where}: model DOF {label!r} already mapped from {seen_model[label]!r}")
        seen_test[dof.node, dof.axis] = str(key)
        seen_model[label] = str(key)
        out.append((dof, label))
    return tuple(out)


def _parse_channels(value: object, source: str) -> tuple[ChannelDof, ...]:
    out: list[ChannelDof] = []
    seen_model: dict[str, object] = {}
    seen_channel: set = set()
    for key, target in _section(value, "channels", source).items():
        where = f"{source}: channels[{key!r}]"
        if isinstance(key, bool) or not isinstance(key, (int, str)):
            raise InputError(f"{where}: channel must be a 0-based index or a channel name, got {key!r}")
        if isinstance(key, int) and key < 0:
            raise InputError(f"{where}: channel index must be >= 0, got {key!r}")
        if isinstance(key, str) and not key.strip():
            raise InputError(f"{where}: channel name must not be blank")
        if key in seen_channel:
            raise InputError(f"{where}: channel {key!r} mapped twice")
        label = _model_dof(target, where)
        sign = 1
        if label[0] in "+-":
            sign = -1 if label[0] == "-" else 1
            label = _model_dof(label[1:], where)
        if label in seen_model:
            raise InputError(f"{where}: model DOF {label!r} already mapped from channel {seen_model[label]!r}")
        seen_channel.add(key)
        seen_model[label] = key
        out.append(ChannelDof(key, label, sign))
    return tuple(out)


def load_mapping(path: str | Path) -> DofMapping:
    """Read and validate a mapping YAML file."""
    import yaml

    path = Path(path)
    if not path.is_file():
        raise InputError(f"mapping file not found: {path}")
    try:
        data = yaml.safe_load(path.read_text())
    except (yaml.YAMLError, UnicodeDecodeError) as exc:
        reason = " ".join(str(exc).split())
        raise InputError(f"{path}: not valid YAML: {reason}") from exc
    return parse_mapping(data, str(path))


def as_mapping(mapping: DofMapping | Mapping | str | Path | None) -> DofMapping | None:
    """A DofMapping from a parsed mapping, a dict with the file's structure, a path or None."""
    if mapping is None or isinstance(mapping, DofMapping):
        return mapping
    if isinstance(mapping, (str, Path)):
        return load_mapping(mapping)
    return parse_mapping(mapping, "<mapping>")
