"""Read a study config: YAML file -> overrides -> the run kind's schema -> checks.

Example (studies/lab_frame.yaml, run kind ``updating``)::

    study: lab_frame
    structure: {name: lab_frame_3dof}
    measured: {builtin: lab_frame, case: base}
    validation:                      # extra measured configurations, predicted, not fitted
      - {case: mass_0.654kg, structure_options: {case: mass_0.654kg},
         measured: {builtin: lab_frame, case: mass_0.654kg}}
    objective: {alpha: 1.0, beta: 1.0}
    budget: {max_evaluations: 50000, stall_iterations: 10, stall_tolerance: 1.0e-8}
    algorithms:
      pso: {algorithm: pso, settings: {swarm_size: 20}}
      sm_initial: {algorithm: sm, settings: {start: initial}, runs: 1}
    runs: 10
    seed: 0

The header fields every kind shares are in :mod:`framework.study.schema`; each kind's own
fields in its module under :mod:`framework.study.kinds`. Overrides from the command line use
dotted paths: ``--set algorithms.pso.settings.swarm_size=40``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from framework.core.errors import InputError
from framework.core.textio import parse_override_value, read_yaml_file
from framework.study.kinds import get_kind
from framework.study.kinds.base import check_report
from framework.study.schema import StudyHeader, format_error, validated

__all__ = ["format_error", "load", "parse_value", "read_with_overrides", "set_path", "validate"]

def parse_value(text: str, source: str = "--set") -> Any:
    """A --set value: YAML scalar/list syntax (``40``, ``1e-6``, ``[5, 10]``, ``true``)."""
    return parse_override_value(text, source)


def set_path(data: dict, dotted: str, value: Any) -> None:
    """Set ``data[a][b][c] = value`` for ``dotted = 'a.b.c'`` (creating mappings)."""
    keys = dotted.split(".")
    if not all(keys):
        raise InputError(f"--set {dotted!r}: empty key in the dotted path")
    node = data
    for key in keys[:-1]:
        if not isinstance(node.get(key), dict):
            node[key] = {}
        node = node[key]
    node[keys[-1]] = value


def read_with_overrides(path: str | Path, overrides: list[str] | None = None, what: str = "config") -> dict:
    """Read a YAML mapping strictly (:mod:`framework.core.textio`) and apply ``key.path=value`` overrides."""
    data = read_yaml_file(Path(path), what=what)
    for item in overrides or []:
        if "=" not in item:
            raise InputError(f"--set {item!r}: expected KEY.PATH=VALUE")
        key, value = item.split("=", 1)
        set_path(data, key.strip(), parse_value(value, source=f"--set {key.strip()}"))
    return data


def validate(data: Any, source: str = "<config>", base_dir: Path | None = None) -> StudyHeader:
    """Validate a config mapping against its run kind's schema and report options
(:func:`framework.study.kinds.base.check_report`); InputError naming file, field, value."""
    if not isinstance(data, dict):
        raise InputError(f"{source}: a study config must be a mapping, got {type(data).__name__}")
    kind_name = data.get("kind", "updating")
    try:
        kind = get_kind(kind_name)
    except InputError as exc:
        raise InputError(f"{source}: {exc}") from None
    cfg = validated(kind.config, data, source, context={"base_dir": base_dir})
    try:
        check_report(kind, cfg.report)
    except InputError as exc:
        raise InputError(f"{source}: {exc}") from None
    if kind.check is not None:
        kind.check(cfg, source, base_dir)
    return cfg


def load(path: str | Path, overrides: list[str] | None = None) -> StudyHeader:
    """Read a YAML config, apply ``key.path=value`` overrides, validate."""
    path = Path(path)
    data = read_with_overrides(path, overrides)
    cfg = validate(data, source=str(path), base_dir=path.parent)
    cfg._source = str(path)
    return cfg
