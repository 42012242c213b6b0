"""Expand a study config into run specs: named variants x sweep grid x the kind's runs.

A run spec is a small, picklable dict::

    {"run_id", "study", "kind", "label", "variant", "seed", "columns", "task", "execution"}

``task`` is everything the run needs (the kind decides what); ``columns`` are the settings
that distinguish this run, written as typed columns into every table; ``execution`` is how
its model evaluations run (the config's ``execution`` section); ``run_id`` is a hash
of what determines the run's result (the kind, its task's identity and the seed) and of
nothing else: not the study name, output folder, backend, progress bars or report options.
So ``--resume`` recognises a stored run, changing a figure option keeps every stored run,
and sweeping one algorithm's setting does not duplicate the runs of the others.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
from typing import Any

from framework.core.errors import InputError
from framework.study.config import set_path, validate
from framework.study.kinds import get_kind
from framework.study.schema import MAX_PLANNED_RUNS, StudyHeader


def canonical(obj: Any) -> str:
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), default=str)


def run_id(kind: str, identity: dict, seed: int) -> str:
    """16 hex digits of sha1 over the kind, the task's identity and the seed."""
    return hashlib.sha1(canonical({"kind": kind, "task": identity, "seed": seed}).encode()).hexdigest()[:16]


def column_names(keys: list[str]) -> dict[str, str]:
    """Column name of each swept dotted path: its last part, or the whole path (``.`` -> ``_``)
    where two swept paths end alike."""
    last = [k.split(".")[-1] for k in keys]
    return {k: (t if last.count(t) == 1 else k.replace(".", "_")) for k, t in zip(keys, last)}


def expand(cfg: StudyHeader) -> list[tuple[str, dict[str, Any], StudyHeader]]:
    """Every (variant name, sweep values, config with both applied)."""
    variants = cfg.variants or {"": {}}
    keys = list(cfg.sweep)
    n = len(variants) * math.prod(len(cfg.sweep[k]) for k in keys)  # counted before any is built
    if n > MAX_PLANNED_RUNS:
        raise InputError(f"study {cfg.study!r}: sweep and variants give {n} variants, more than the limit of "
                         f"{MAX_PLANNED_RUNS}")
    combos = list(itertools.product(*(cfg.sweep[k] for k in keys))) if keys else [()]
    if not cfg.variants and not keys:
        return [("", {}, cfg)]
    base = cfg.model_dump(mode="json")
    base["sweep"], base["variants"] = {}, {}
    out = []
    for name, overrides in variants.items():
        for combo in combos:
            data = json.loads(json.dumps(base))
            for key, value in overrides.items():
                set_path(data, key, value)
            values = dict(zip(keys, combo))
            for key, value in values.items():
                set_path(data, key, value)
            where = ", ".join(filter(None, [f"variant {name!r}" if name else "", f"sweep {values}" if values else ""]))
            out.append((name, values, validate(data, source=f"{cfg.study} ({where})")))
    return out


def variant_label(name: str, values: dict[str, Any], names: dict[str, str]) -> str:
    parts = [name] if name else []
    parts += [f"{names[k]}={v}" for k, v in values.items()]
    return ",".join(parts) or "default"


def plan(cfg: StudyHeader) -> list[dict]:
    """All run specs of a study, in a stable order, without duplicates; an InputError names
    the config file the study was read from."""
    try:
        return _plan(cfg)
    except InputError as exc:
        source = getattr(cfg, "_source", "")
        if source and not str(exc).startswith(source):
            raise InputError(f"{source}: {exc}") from None
        raise


def _plan(cfg: StudyHeader) -> list[dict]:
    kind = get_kind(cfg.kind)
    names = column_names(list(cfg.sweep))
    specs: list[dict] = []
    seen: set[str] = set()
    for name, values, vcfg in expand(cfg):
        execution = vcfg.execution.model_dump(mode="json")
        for part in kind.plan_runs(vcfg, values):
            relevant = {k: v for k, v in values.items() if k in part.get("relevant", values)}
            columns = {names[k]: _scalar(v) for k, v in relevant.items()}
            columns.update(part.get("columns", {}))
            spec = {
                "study": cfg.study,
                "kind": cfg.kind,
                "label": part["label"],
                "variant": variant_label(name, relevant, names),
                "seed": int(part["seed"]),
                "columns": columns,
                "task": part["task"],
                "execution": execution,
            }
            spec["run_id"] = run_id(cfg.kind, kind.identity_of(part["task"]), spec["seed"])
            if spec["run_id"] in seen:
                continue
            seen.add(spec["run_id"])
            specs.append(spec)
            if len(specs) > MAX_PLANNED_RUNS:
                raise InputError(f"study {cfg.study!r}: more than {MAX_PLANNED_RUNS} runs planned")
    return specs


def _scalar(value: Any) -> Any:
    """A column value: scalars as they are, anything else as canonical JSON text."""
    if value is None or isinstance(value, bool | int | float | str):
        return value
    return canonical(value)
